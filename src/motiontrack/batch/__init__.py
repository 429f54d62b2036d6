"""Many videos, one ``track`` run each, on a local or remote Dask cluster (``motiontrack batch``).

From Python, :func:`run_batch` is the one entry point::

    import motiontrack.batch
    rows = motiontrack.batch.run_batch(["videos/"], "results", "cfg.toml", client=client)
"""

from .runner import INDEX_COLUMNS, INDEX_FILE, config_hash, run_batch, run_video
from .sources import Video, expand_sources

__all__ = ["INDEX_COLUMNS", "INDEX_FILE", "Video", "config_hash", "expand_sources", "run_batch",
           "run_video"]
