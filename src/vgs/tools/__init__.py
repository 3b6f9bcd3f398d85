"""User tools around the runs: one episode watched (:mod:`~vgs.tools.demo`,
:mod:`~vgs.tools.demofigure`), the cell exported as MJCF (:mod:`~vgs.tools.scene`), a trained
network exported as a portable policy (:mod:`~vgs.tools.export_policy`) and a finished
reproduction published under docs/results (:mod:`~vgs.tools.publish`)."""
