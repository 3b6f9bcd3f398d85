"""One instrument on every CPU: the golden episodes give the same bits whatever BLAS kernel
OpenBLAS runs, whatever SIMD width numpy dispatches to, whatever PyTorch's CPU capability.

Each variant re-runs every golden case (``tests/golden/cases.py --check``) in a subprocess whose
environment selects another kernel, and requires the records of ``tests/golden/records.json``
field by field. The per-tick maths of the cell and the controller runs on Python floats and
MuJoCo's own routines (:mod:`vgs.vecmath`, docs/architecture.md "One instrument on every CPU"),
so no kernel choice may move an episode; a change of a controller constant moves every variant
and fails here as in ``tests/test_golden_records.py``.

The host's own setting of ``OPENBLAS_CORETYPE`` (some hosts set it) is one of the variants and
is never changed for the rest of the suite.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import mujoco
import pytest

sys.path.insert(0, str(Path(__file__).parent / "golden"))
from cases import RECORDS  # noqa: E402

CASES_SCRIPT = Path(__file__).parent / "golden" / "cases.py"
GOLDEN_VERSION = json.loads(RECORDS.read_text())["mujoco_version"]


def _has_avx512() -> bool:
    try:
        return "avx512f" in Path("/proc/cpuinfo").read_text()
    except OSError:
        return False


def variants() -> list[tuple[str, dict[str, str | None]]]:
    """(name, environment changes; None removes a variable) of every kernel variant."""
    host = os.environ.get("OPENBLAS_CORETYPE")
    out: list[tuple[str, dict[str, str | None]]] = [
        (f"host (OPENBLAS_CORETYPE={host or 'unset'})", {}),
        ("OPENBLAS_CORETYPE=Haswell", {"OPENBLAS_CORETYPE": "Haswell"}),
        ("OPENBLAS_CORETYPE=Sandybridge", {"OPENBLAS_CORETYPE": "Sandybridge"}),
        ("OPENBLAS_CORETYPE=Prescott", {"OPENBLAS_CORETYPE": "Prescott"}),
        # numpy's own SIMD dispatch cut to its x86-64-v2 baseline, torch at its plainest.
        ("numpy baseline SIMD, ATEN_CPU_CAPABILITY=default",
         {"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
          "ATEN_CPU_CAPABILITY": "default"}),
        ("ATEN_CPU_CAPABILITY=avx2", {"ATEN_CPU_CAPABILITY": "avx2"}),
    ]
    if _has_avx512():
        out.append(("OPENBLAS_CORETYPE=SkylakeX", {"OPENBLAS_CORETYPE": "SkylakeX"}))
    return out


def _environment(changes: dict[str, str | None]) -> dict[str, str]:
    env = dict(os.environ)
    env["OPENBLAS_NUM_THREADS"] = "1"
    for key, value in changes.items():
        if value is None:
            env.pop(key, None)
        else:
            env[key] = value
    return env


@pytest.mark.skipif(mujoco.__version__ != GOLDEN_VERSION,
                    reason=f"golden records made with MuJoCo {GOLDEN_VERSION}")
def test_every_kernel_gives_the_golden_records() -> None:
    """All variants, two at a time (one per core), each must print 'identical'."""
    pending = variants()
    failures: list[str] = []
    while pending:
        batch, pending = pending[:2], pending[2:]
        procs = [(name, subprocess.Popen([sys.executable, str(CASES_SCRIPT), "--check"],
                                         env=_environment(changes), stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, text=True))
                 for name, changes in batch]
        for name, proc in procs:
            out, _ = proc.communicate(timeout=600)
            if proc.returncode != 0:
                failures.append(f"{name}:\n{out[-2000:]}")
    assert not failures, "records differ under:\n" + "\n".join(failures)


PUBLISHED_POLICY = Path(__file__).resolve().parents[1] / "docs/results/paper_light_s0/vgs"


@pytest.mark.skipif(not PUBLISHED_POLICY.exists(), reason="no published policy in this checkout")
def test_a_published_policy_picks_the_same_pixels_under_every_torch_capability() -> None:
    """The network keeps PyTorch's vectorised kernels; its choice may move only between two
    pixels whose Q values tie within a few bfloat16 steps (200 scenes: ``python
    tests/golden/pixels.py --policy docs/results/paper_light_s0/vgs``; on an AVX2-only AMD
    EPYC one of these 6 scenes flips so, on an AVX-512 Xeon none)."""
    from pixels import compare

    same, ties, total, line = compare(str(PUBLISHED_POLICY), 6, ("default", "avx2", "avx512"))
    assert same + ties == total, f"{total - same} of {total} pixels flip; {line}"
    assert same >= total - 1, line  # a near tie is rare: more than one in 6 is not
