"""Helpers the test modules import (``from helpers import ann, require``): real data, tables,
ports and subprocesses, and tracked runs shared by the session. Fixtures stay in conftest.py."""

from helpers.data import REPO, data_root, require
from helpers.procs import communicate_or_dump, cpu_burners, enable_ctrl_c, free_port
from helpers.runs import SceneRun, SceneRuns
from helpers.tables import ann, tracks_of

__all__ = ["REPO", "SceneRun", "SceneRuns", "ann", "communicate_or_dump", "cpu_burners",
           "data_root", "enable_ctrl_c", "free_port", "require", "tracks_of"]
