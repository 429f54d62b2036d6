"""The run layer: one job loop under every command.

A :class:`Job` owns a source, a per-frame processor (:mod:`.processors`) and output writers
(:mod:`.writers`); it handles interruption, failed sources, atomic finalisation and ``--force``,
and reports progress through a callback. :mod:`.jobs` builds the job of each command.
"""

from .job import Job, JobContext, JobSummary, Processor, RunOutcome, Writer
from .jobs import dense_flow_job, follow_job, overlay_job, sparse_flow_job, track_job

__all__ = ["Job", "JobContext", "JobSummary", "Processor", "RunOutcome", "Writer", "track_job",
           "follow_job", "sparse_flow_job", "dense_flow_job", "overlay_job"]
