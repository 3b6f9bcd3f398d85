"""One colour per policy in every figure (report, curves, seeds, demo), and the colours of the
two gain measures, which are not policies."""

from __future__ import annotations

POLICY_COLORS = {"baseline": "tab:blue", "vgs": "tab:red", "center": "tab:gray",
                 "random": "tab:green", "com-oracle": "tab:olive"}
OTHER_POLICY = "tab:purple"  # a user's module:function policy
# The gains of VGS over the baseline (vgs seeds): on the mean time of the successes, on the
# total time of all tests; the paper's value as a reference line.
GAIN_COLORS = {"gain": "tab:brown", "total_gain": "tab:cyan", "paper": "0.35"}
LINESTYLES = ("-", "--", "-.", ":")  # several runs of one policy (training seeds)


def policy_color(policy: str) -> str:
    """The colour of ``policy`` (``baseline``, ``vgs``, ``center``, ``random``,
    ``com-oracle``; a training run's mode), :data:`OTHER_POLICY` for any other."""
    return POLICY_COLORS.get(str(policy), OTHER_POLICY)
