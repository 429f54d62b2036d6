"""Many videos, one ``track`` run each, on a local or remote Dask cluster (``motiontrack batch``)."""

import sys as _sys
import types as _types
from typing import Any as _Any

from .runner import INDEX_COLUMNS, INDEX_FILE, config_hash, run_batch, run_video
from .sources import Video, expand_sources

__all__ = ["INDEX_COLUMNS", "INDEX_FILE", "Video", "config_hash", "expand_sources", "run_batch",
           "run_video"]


class _Callable(_types.ModuleType):
    """``motiontrack.batch`` is this package once imported and the function
    :func:`motiontrack.batch` before: both calls do the same."""

    def __call__(self, *args: _Any, **kwargs: _Any) -> _Any:
        from .. import batch_videos

        return batch_videos(*args, **kwargs)


_sys.modules[__name__].__class__ = _Callable
