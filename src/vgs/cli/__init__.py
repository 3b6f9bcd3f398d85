"""The ``vgs`` command: ``demo``, ``sweep``, ``export-scene``, ``export-policy``,
``model-info``, ``train``, ``heatmap``, ``curves``, ``evaluate``, ``reproduce``, ``report``,
``seeds``, ``grasp-sites``, ``status`` and ``config``.

Each command takes only the flags it uses. Those that build a configuration from a profile
(``demo``, ``sweep``, ``export-scene``, ``train``, ``evaluate``, ``reproduce`` and ``config``)
take ``--profile``, the cell's override flags (``--peg-mass`` ...) and the generic ``--set
key=value`` with a dotted path into :class:`vgs.config.ExperimentConfig`; ``model-info`` takes
``--profile`` and ``--set`` of ``network.*`` keys only; the commands that read run folders
(``heatmap``, ``curves``, ``report``, ``seeds``, ``grasp-sites``, ``status``,
``export-policy``) take none of
them: a run's configuration is the one it recorded. ``vgs config`` lists every key with its
value and documentation. Bad input,
whether argparse rejects it or a :class:`vgs.errors.VGSError` is raised, ends with one line
``vgs: error: <field>: <message>`` on stderr and exit code 2; so do an OS error on a file or
folder (an ``--out`` that is a file, a full disk) and a corrupt file of a run folder. Ctrl-C
ends with one line saying how to resume and exit code 130.

The package: :mod:`vgs.cli.parser` (the parser and :func:`main`), :mod:`vgs.cli.options` (the
configuration from the flags), :mod:`vgs.cli.runs` (the commands that run something) and
:mod:`vgs.cli.folders` (the commands that read run folders); ``python -m vgs.cli`` runs it.
"""

from vgs.cli.options import (
    OVERRIDE_FLAGS,
    UsageError,
    apply_override,
    check_hole_fits,
    config_from_args,
    parse_value,
)
from vgs.cli.parser import RESUMABLE, build_parser, main

__all__ = [
    "OVERRIDE_FLAGS", "RESUMABLE", "UsageError", "apply_override", "build_parser",
    "check_hole_fits", "config_from_args", "main", "parse_value",
]
