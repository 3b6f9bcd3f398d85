"""Running episodes of a policy: which grasp each policy chooses (:mod:`~vgs.rollout.policies`:
the centre heuristic, random grasps, a trained network) and where the episodes run
(:mod:`~vgs.rollout.episodepool`: in this process, a process pool or Ray, with the same rows
whatever the backend)."""
