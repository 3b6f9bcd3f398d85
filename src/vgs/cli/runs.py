"""The commands that build a configuration and run the cell or the network: ``demo``, ``sweep``,
``export-scene``, ``model-info``, ``train``, ``evaluate``, ``reproduce`` and ``config``."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from vgs.cli.options import (
    check_video_name,
    config_label,
    flag_overrides,
    headless_gl_default,
    parse_offsets_mm,
    parse_video_size,
)
from vgs.config import ExperimentConfig
from vgs.errors import ConfigError
from vgs.jsonsafe import dumps


def cmd_demo(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """One traced episode: phase table (or JSON record), DIR/demo.png and, with ``--video``,
    ``--trace``, ``--rerun``, the episode as a video, a per-tick Parquet table, a Rerun
    recording."""
    out = Path(args.out)
    extra = [Path(name) for name in (args.video, args.trace, args.rerun) if name]
    targets = [out / "demo.png", *extra]
    existing = [str(path) for path in targets if path.exists() or path.is_symlink()]
    if existing and not args.force:  # before the episode, not after it
        raise ConfigError("demo", f"{', '.join(existing)} exists; add --force to overwrite, or "
                                  "give another --out/--video/--trace/--rerun")
    video_size = parse_video_size(args.video_size) if args.video else None
    if args.trace or args.rerun:
        from vgs.tools.trace import check_trace_name, require_rerun

        if args.trace:
            check_trace_name(args.trace)
        if args.rerun:
            require_rerun(args.rerun)
    if args.video:
        check_video_name(args.video)
        headless_gl_default()  # before anything imports mujoco
        from vgs.render import require_gl, require_video_writer

        require_video_writer(args.video)  # before the episode, not after it
        require_gl()
    from vgs.config import condition_peg
    from vgs.tools.demo import format_report, run_demo
    from vgs.tools.demofigure import demo_figure

    seed = cfg.seed if args.seed is None else args.seed
    peg = condition_peg(cfg.cell.peg, cfg.eval, args.condition, 1.0)
    progress = None if args.no_progress else _demo_progress
    started = time.monotonic()
    result = run_demo(cfg, seed, args.offset / 1000.0, policy=args.policy, peg=peg,
                      progress=progress)
    if progress is not None:
        print(f"demo: episode done, {result.trace.time[-1]:.1f} s simulated in "
              f"{time.monotonic() - started:.0f} s wall", file=sys.stderr, flush=True)
    out.mkdir(parents=True, exist_ok=True)
    written = [("figure", demo_figure(result, out / "demo.png"))]
    if args.video and video_size is not None:
        from vgs.tools.demo import demo_video

        written.append(("video", demo_video(result, cfg.cell, args.video, fps=args.video_fps,
                                            speed=args.video_speed, width=video_size[0],
                                            height=video_size[1], camera=args.camera)))
    if args.trace:
        from vgs.tools.trace import write_trace

        written.append(("trace", write_trace(result, args.trace)))
    if args.rerun:
        from vgs.tools.trace import write_rerun

        written.append(("recording", write_rerun(result, args.rerun)))
    if args.json:
        print(dumps(result.record.to_row()))
    else:
        print(format_report(result.record))
        print()
        for label, path in written:
            print(f"{label:<15} {path}")
    return 0


def _demo_progress(simulated: float, wall: float) -> None:
    """One progress line of ``vgs demo`` on stderr (every 2 s of wall time)."""
    print(f"demo: episode at {simulated:.1f} s simulated, {wall:.0f} s wall", file=sys.stderr,
          flush=True)


def cmd_sweep(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Grasp-offset sweep: DIR/sweep.csv, DIR/sweep.png and DIR/summary.json."""
    from vgs.experiments.sweep import SweepSpec, default_offsets, sweep_to_folder

    if args.offsets_mm is not None:
        offsets = parse_offsets_mm(args.offsets_mm)
    else:
        offsets = default_offsets(cfg.cell.peg, args.offsets, args.length_range)
    spec = SweepSpec(offsets=offsets, trials=args.trials, mass_range=args.mass_range,
                     length_range=args.length_range,
                     seed=cfg.seed if args.seed is None else args.seed)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)  # an unusable --out fails now, not after the sweep
    summary = sweep_to_folder(cfg, spec, out, workers=args.workers,
                              progress=not args.no_progress)
    print(f"{'offset [mm]':>11}  {'n':>3}  {'success':>7}  {'mean [s]':>8}  {'std [s]':>7}  "
          f"{'min [s]':>7}  {'max [s]':>7}")
    for s in summary:
        cells = [s[k] for k in ("time_mean_s", "time_std_s", "time_min_s", "time_max_s")]
        times = "  ".join(f"{'-':>8}" if v is None else f"{v:8.2f}" for v in cells)
        print(f"{s['offset_mm']:11.1f}  {s['n']:3d}  {100 * s['success_rate']:6.0f}%  {times}")
    doc = json.loads((out / "summary.json").read_text())
    paired = doc["paired"]
    if len(doc.get("hosts", [])) > 1:
        print(f"\nnote: the rows come from several hosts ({'; '.join(doc['hosts'])}); the same "
              "scene can end differently on another CPU")
    if paired["vs_center"]:
        print("\npaired against the centre grasp (same scenes; both assembled), 95 % CI:")
        for e in paired["vs_center"]:
            lo, hi = e["time_diff_ci_s"]
            print(f"{e['offset_mm']:11.1f}  dT {_num(e['time_diff_s'])} s [{_num(lo)}, "
                  f"{_num(hi)}]  pairs {e['pairs']}")
    slope = paired["slope"]
    if slope["time_s_per_mm"] is not None:
        lo, hi = slope["time_ci_s_per_mm"]
        print(f"time vs |offset|: {_num(slope['time_s_per_mm'], 3)} s/mm [{_num(lo, 3)}, "
              f"{_num(hi, 3)}]")
    print(f"\nwrote {out / 'sweep.csv'}, {out / 'sweep.png'}, {out / 'summary.json'}")
    return 0


def _num(value: float | None, digits: int = 2) -> str:
    """A number for a table, or '-' when there is none."""
    return "-" if value is None or value != value else f"{value:+.{digits}f}"


def cmd_export_scene(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Write the compiled cell as MJCF and check that MuJoCo loads it."""
    from vgs.tools.scene import CONTROL_HINT, export_scene

    info = export_scene(cfg, args.out, seed=args.seed)
    print(f"wrote {info.path} ({info.nbody} bodies, {info.ngeom} geoms, {info.nmesh} meshes, "
          f"{info.nu} actuators, cameras {', '.join(info.cameras)}); it opens at home with the "
          f"peg on the table (seed {args.seed}) and holds still until you act; open it with: "
          f"python -m mujoco.viewer --mjcf {info.path}  (Python: mujoco.MjModel.from_xml_path; "
          f"{CONTROL_HINT}; the stick weld pad_stiction is off: docs/cell.md)")
    return 0


def cmd_model_info(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Parameter counts and tensor shapes of the grasp network."""
    from vgs.grasping.network import format_model_info, model_info

    cfg = flag_overrides(cfg, args, {"backbone": "network.backbone",
                                     "rotations": "network.num_rotations",
                                     "rotate": "network.rotate"})
    info = model_info(cfg.network, rotate=cfg.network.rotate, size=args.size)
    print(dumps(info, indent=2) if args.json else format_model_info(info))
    return 0


def cmd_train(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Train (or resume) the VGS or baseline grasp policy."""
    from vgs.experiments.train import train

    cfg = flag_overrides(cfg, args, {"episodes": "train.episodes",
                                     "backbone": "network.backbone", "seed": "seed",
                                     "device": "train.device",
                                     "workers": "train.parallel_episodes"})
    out = train(cfg, args.mode, Path(args.out), progress=not args.no_progress,
                backend=args.backend, ray_address=args.ray_address)
    if (out / "checkpoint.pt").exists():
        print(f"run in {out}: episodes.csv, tensorboard/, checkpoint.pt")
    else:
        print(f"{out} holds a finished run kept as its final network (policy.pt): nothing to "
              "train")
    return 0


def cmd_evaluate(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Evaluate one policy on one condition: DIR/episodes.parquet, .csv and summary.json."""
    from vgs.analysis.stats import summarize
    from vgs.experiments.evaluate import EvalSpec, evaluate

    episodes = cfg.eval.episodes if args.episodes is None else args.episodes
    for flag in ("videos", "traces"):  # before the evaluation, not after it
        count = getattr(args, flag)
        if not 0 <= count <= episodes:
            raise ConfigError(f"--{flag}", f"must lie in [0, {episodes}] (the episodes "
                                           f"evaluated), got {count}")
    if args.videos:
        headless_gl_default()  # before anything imports mujoco
        from vgs.render import require_gl

        require_gl()  # before the evaluation, not after it
    spec = EvalSpec(args.policy, args.condition, episodes,
                    cfg.reproduce.eval_seed if args.seed is None else args.seed)
    df = evaluate(cfg, spec, Path(args.out), workers=args.workers, backend=args.backend,
                  ray_address=args.ray_address, progress=not args.no_progress)
    videos: list[Path] = []
    traces: list[Path] = []
    if args.videos or args.traces:
        from vgs.tools.trace import evaluation_outputs

        videos, traces = evaluation_outputs(cfg, spec, Path(args.out), args.videos, args.traces,
                                            df, camera=args.camera)
    s = summarize(df)
    if args.json:
        print(dumps(s, indent=2))
        return 0
    print(f"{df['policy'].iloc[0]} / {args.condition}: {s['episodes']} episodes, success "
          f"{s['success_rate']:.1%}, grasp {s['grasp_success_rate']:.1%}")
    if s["time_mean_s"] is not None:
        print(f"assembly time [s]: mean {s['time_mean_s']:.2f}, std {s['time_std_s']:.2f}, "
              f"min {s['time_min_s']:.2f}, max {s['time_max_s']:.2f}; total "
              f"{s['time_total_h']:.3f} h")
    if s["failure_reasons"]:
        print("failures: " + ", ".join(f"{k} x{v}" for k, v in s["failure_reasons"].items()))
    print(f"wrote {Path(args.out) / 'episodes.parquet'} (and .csv, summary.json)")
    if videos:
        print(f"videos {', '.join(str(v) for v in videos)}")
    if traces:
        print(f"traces {', '.join(str(t) for t in traces)}")
    return 0


def cmd_reproduce(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Train both policies, evaluate them on the three conditions, sweep, report."""
    from vgs.experiments.reproduce import Reproduction

    names = [name.strip() for name in args.stages.split(",") if name.strip()]
    unknown = [name for name in names if name not in ("train", "evaluate", "sweep", "report")]
    if unknown or not names:  # checked before the folder is touched
        raise ConfigError("stages", f"unknown stage {unknown[0] if unknown else ''!r}; choose "
                                    "from train, evaluate, sweep, report")
    rep = Reproduction(cfg, Path(args.out), workers=args.workers, backend=args.backend,
                       ray_address=args.ray_address, progress=not args.no_progress)
    stages = {"train": rep.train, "evaluate": rep.evaluate, "sweep": rep.sweep,
              "report": rep.report}
    for name in stages:  # always in pipeline order
        if name in names:
            stages[name]()
    if "report" in names:
        path = rep.out / "report.md"
        print(f"wrote {path} and {path.with_suffix('.html')}")
    return 0


def cmd_config(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Print every settable key of the resolved configuration with its value and its doc."""
    from vgs.configdoc import format_settings, settings

    items = settings(cfg)
    if args.json:
        print(dumps([{"key": s.key, "value": s.value, "doc": s.doc} for s in items],
                    indent=2))
        return 0
    print(f"# {config_label(args)}, resolved; each key takes --set KEY=VALUE (a Python "
          "literal or text)")
    print(format_settings(items))
    return 0
