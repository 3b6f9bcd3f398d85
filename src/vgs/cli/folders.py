"""The commands that read run folders and take no configuration flags: ``export-policy``,
``heatmap``, ``curves``, ``report``, ``seeds``, ``grasp-sites`` and ``status``; a run's
configuration is the one it recorded."""

from __future__ import annotations

import argparse
import os
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
            assembly = (f"{'skipped':>8} {'-':>7}" if s["assembly_skipped"] else
                        f"{s['assembly_success']:>8.2f} {s['assembly_time_mean_s']:>7.1f}")
            stops = (f"  ({s['threshold_stops']} assemblies stopped at the threshold)"
                     if s["threshold_stops"] else "")
            print(f"{label:<28} {phase:<12} {s['episodes']:>4} {s['grasp_success']:>6.2f} "
                  f"{assembly} {s['abs_offset_mean_mm']:>8.1f} {s['reward_mean']:>6.3f}{stops}")
    print(f"wrote {args.out}")
    return 0


def cmd_report(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Build DIR/report.md and DIR/report.html from the results in DIR."""
    from vgs.analysis.report import build_report

    if args.publish:  # before anything is written
        from vgs.tools.publish import check_dest

        check_dest(Path(args.dir), Path(args.publish))
    path = build_report(Path(args.dir), **({"title": args.title} if args.title else {}),
                        center=Path(args.center) if args.center else None)
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

    path = seeds_report([Path(d) for d in args.dirs], Path(args.out),
                        center=Path(args.center) if args.center else None)
    print(path.read_text().split("![", 1)[0].rstrip())
    print(f"\nwrote {path}, {path.with_suffix('.csv')}, {path.with_suffix('.png')} and "
          f"{path.with_name('profile.png')}")
    return 0


def cmd_grasp_sites(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Print where on the peg each test grasp of a reproduction lay, and what assembled."""
    from vgs.analysis.graspsites import grasp_sites_report

    if args.workers is not None and args.workers < 1:
        raise ConfigError("workers", f"must be >= 1, got {args.workers}")
    workers = args.workers or os.cpu_count() or 1
    print(grasp_sites_report(Path(args.dir), args.policy, args.condition,
                             Path(args.csv) if args.csv else None,
                             progress=not args.no_progress, workers=workers), end="")
    if args.csv:
        print(f"wrote {args.csv}")
    return 0


def cmd_com_fit(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Fit a shifted-mass sweep's times against the grasp's distances from the middle and from
    the centre of mass, beside its uniform twin (issue 55)."""

    from vgs.analysis.comfit import analyse, markdown
    from vgs.errors import ConfigError
    from vgs.jsonsafe import dumps
    from vgs.runfolder.common import read_table

    tables = []
    for folder in (args.dir, args.twin):
        if folder is None:
            tables.append(None)
            continue
        path = Path(folder) / "sweep.csv"
        if not path.is_file():
            raise ConfigError("dir", f"{folder} holds no sweep.csv (a vgs sweep folder)")
        df = read_table(path)
        need = {"offset_mm", "trial", "assembly_success", "assembly_time_s", "time_align_s",
                "grasp_offset_mm", "grasp_offset_com_mm", "peg_com_shift_mm"}
        missing = sorted(need - set(df.columns))
        if missing:
            raise ConfigError("dir", f"{path} lacks {', '.join(missing)} (a sweep made "
                                     "before the peg's centre of mass was recorded)")
        tables.append(df)
    doc = analyse(tables[0], tables[1])
    text = markdown(doc)
    print(text, end="")
    if args.out:
        out = Path(args.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "com_fit.md").write_text(text)
        (out / "com_fit.json").write_text(dumps(doc, indent=1) + "\n")
        print(f"wrote {out / 'com_fit.md'}, {out / 'com_fit.json'}")
    return 0


def cmd_status(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Print the progress of the jobs in a reproduce, train or evaluate folder."""
    from vgs.runfolder.status import format_status

    print(format_status(Path(args.dir)))
    return 0
