"""The runners: the commands that run episodes and write run folders.

:mod:`~vgs.experiments.train` (one training run of the grasp network), :mod:`~vgs.experiments.
evaluate` (one policy on one test condition), :mod:`~vgs.experiments.sweep` (the paired
grasp-offset sweep) and :mod:`~vgs.experiments.reproduce` (the paper's protocol: trainings,
tests, sweep, report). They run episodes through :mod:`vgs.rollout`, keep their folders with
:mod:`vgs.runfolder` and summarise with :mod:`vgs.analysis`.
"""
