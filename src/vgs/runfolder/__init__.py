"""Run-folder machinery: what makes a run folder checksummed, resumable and safe to share.

:mod:`~vgs.runfolder.common` (lock, atomic JSON, the request against the recorded
configuration, host and provenance), :mod:`~vgs.runfolder.folderkind` (one kind per folder),
:mod:`~vgs.runfolder.journal` (append-only journals of rows and the rule for a torn last line),
:mod:`~vgs.runfolder.trainfolder` (a training run's checkpoint and its checks),
:mod:`~vgs.runfolder.layout` (where a reproduction keeps its trainings and evaluations) and
:mod:`~vgs.runfolder.status` (``vgs status``). Torch-free except the training checkpoint.
"""
