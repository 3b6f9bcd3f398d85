"""From tables to findings: the statistics (:mod:`~vgs.analysis.stats`, :mod:`~vgs.analysis.
sweepstats`), the reproduction report (:mod:`~vgs.analysis.report` with its document,
figures, learning curves and Q heat maps), the table across training seeds
(:mod:`~vgs.analysis.seeds`) and the sweep's figure (:mod:`~vgs.analysis.sweepfigure`). It
reads run folders and writes documents and figures; it runs no episode (a heat map only
observes a few training scenes)."""
