"""The commands that read run folders and take no configuration flags: ``export-policy``,
``heatmap``, ``curves``, ``report``, ``seeds``, ``grasp-sites`` and ``status``; a run's
configuration is the one it recorded."""

from __future__ import annotations

import argparse
from pathlib import Path

from vgs.config import ExperimentConfig
from vgs.errors import ConfigError
from vgs.jsonsafe import dumps

MAX_HEATMAP_SCENES = 16  # rows of the figure


def cmd_export_policy(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Write a training run's network as plain weights plus a JSON description."""
    from vgs.tools.export_policy import export_policy

    written = export_policy(Path(args.run_dir), Path(args.out))
    print(f"wrote {written.weights} ({written.parameters} values; "
          f"torch.load(path, weights_only=True)) and {written.description}; the plain-torch "
          f"snippet that runs them: docs/grasping.md, 'Using a trained network without vgs'")
    if written.run_json is not None:
        print(f"and {written.run_json}: vgs evaluate --policy {written.weights.parent} loads "
              "the folder without the checkpoint")
    return 0


def cmd_heatmap(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Q-value heat maps of a training run, untrained beside trained (paper Figure 7)."""
    from vgs.analysis.heatmap import plot_heatmaps

    if not 1 <= args.scenes <= MAX_HEATMAP_SCENES:
        raise ConfigError("scenes", f"must lie in [1, {MAX_HEATMAP_SCENES}], got {args.scenes}")
    out = plot_heatmaps(Path(args.run_dir), Path(args.out), scenes=args.scenes)
    print(f"wrote {out}")
    return 0


def cmd_curves(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Learning curves of runs and where each policy grasps; prints a summary table."""
    from vgs.analysis.curves import plot_curves

    summaries = plot_curves([Path(r) for r in args.runs], Path(args.out), window=args.window)
    if args.json:
        print(dumps(summaries, indent=2))
        return 0
    print(f"{'run':<28} {'phase':<12} {'n':>4} {'grasp':>6} {'assembly':>8} {'T [s]':>7} "
          f"{'|l| [mm]':>8} {'reward':>6}")
    for label, phases in summaries.items():
        for phase, s in phases.items():
            print(f"{label:<28} {phase:<12} {s['episodes']:>4} {s['grasp_success']:>6.2f} "
                  f"{s['assembly_success']:>8.2f} {s['assembly_time_mean_s']:>7.1f} "
                  f"{s['abs_offset_mean_mm']:>8.1f} {s['reward_mean']:>6.3f}")
    print(f"wrote {args.out}")
    return 0


def cmd_report(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Build DIR/report.md and DIR/report.html from the results in DIR."""
    from vgs.analysis.report import build_report

    if args.publish:  # before anything is written
        from vgs.tools.publish import check_dest

        check_dest(Path(args.dir), Path(args.publish))
    path = build_report(Path(args.dir), **({"title": args.title} if args.title else {}))
    print(f"wrote {path} and {path.with_suffix('.html')}")
    if args.publish:
        from vgs.tools.publish import publish

        files = publish(Path(args.dir), Path(args.publish))
        nets = [f for f in files if f.name == "policy.pt"]
        print(f"copied {len(files)} result files (no checkpoints) to {args.publish}" + (
            f", with the final networks of {len(nets)} runs "
            f"({sum(f.stat().st_size for f in nets) / 1e6:.1f} MB: "
            f"{', '.join(str(f.parent) for f in nets)}; vgs evaluate --policy FOLDER loads "
            "each)" if nets else ""))
    return 0


def cmd_seeds(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Compare VGS with the baseline across the training runs of several results folders."""
    from vgs.analysis.seeds import seeds_report

    path = seeds_report([Path(d) for d in args.dirs], Path(args.out))
    print(path.read_text().split("![", 1)[0].rstrip())
    print(f"\nwrote {path}, {path.with_suffix('.csv')} and {path.with_suffix('.png')}")
    return 0


def cmd_grasp_sites(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Print where on the peg each test grasp of a reproduction lay, and what assembled."""
    from vgs.analysis.graspsites import grasp_sites_report

    print(grasp_sites_report(Path(args.dir), args.policy, args.condition,
                             Path(args.csv) if args.csv else None,
                             progress=not args.no_progress), end="")
    if args.csv:
        print(f"wrote {args.csv}")
    return 0


def cmd_status(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Print the progress of the jobs in a reproduce, train or evaluate folder."""
    from vgs.runfolder.status import format_status

    print(format_status(Path(args.dir)))
    return 0
