"""The ``vgs`` command: ``demo``, ``sweep``, ``export-scene``, ``export-policy``,
``model-info``, ``train``, ``heatmap``, ``curves``, ``evaluate``, ``reproduce``, ``report``,
``seeds``, ``status`` and ``config``.

Each command takes only the flags it uses. Those that build a configuration from a profile
(``demo``, ``sweep``, ``export-scene``, ``train``, ``evaluate``, ``reproduce`` and ``config``)
take ``--profile``, the cell's override flags (``--peg-mass`` ...) and the generic ``--set
key=value`` with a dotted path into :class:`vgs.config.ExperimentConfig`; ``model-info`` takes
``--profile`` and ``--set`` of ``network.*`` keys only; the commands that read run folders
(``heatmap``, ``curves``, ``report``, ``seeds``, ``status``, ``export-policy``) take none of
them: a run's configuration is the one it recorded. ``vgs config`` lists every key with its
value and documentation. Bad input,
whether argparse rejects it or a :class:`vgs.errors.VGSError` is raised, ends with one line
``vgs: error: <field>: <message>`` on stderr and exit code 2; so do an OS error on a file or
folder (an ``--out`` that is a file, a full disk) and a corrupt file of a run folder. Ctrl-C
ends with one line saying how to resume and exit code 130.
"""

from __future__ import annotations

import argparse
import ast
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import is_dataclass
from pathlib import Path
from typing import Any, NoReturn

from vgs.config import NO_SUCH_FIELD, ExperimentConfig, PegConfig, override, profile
from vgs.errors import ConfigError, VGSError
from vgs.jsonsafe import dumps
from vgs.validate import check_config

# Flag -> dotted configuration path. Values are SI (m, kg, N).
OVERRIDE_FLAGS: dict[str, str] = {
    "peg_mass": "cell.peg.mass",
    "peg_length": "cell.peg.length",
    "peg_diameter": "cell.peg.diameter",
    "clearance": "cell.hole.clearance",
    "hole_depth": "cell.hole.depth",
    "gripper_force": "cell.gripper.force",
}


class UsageError(VGSError):
    """Command-line input that argparse rejects."""


class _Parser(argparse.ArgumentParser):
    """An argument parser that raises instead of printing usage and exiting."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(message)


# -- configuration from the command line -----------------------------------------------------


def parse_value(text: str) -> Any:
    """A Python literal if ``text`` is one, else the text itself."""
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text


def _current(cfg: Any, path: str) -> Any:
    """The value at the dotted ``path`` of ``cfg``, or None if there is none."""
    for name in path.split("."):
        cfg = getattr(cfg, name, None)
    return cfg


def apply_override(cfg: ExperimentConfig, path: str, value: Any) -> ExperimentConfig:
    """``override(cfg, path, value)`` with every bad value reported as a ConfigError.

    A tuple field given text that is not a Python literal takes its comma-separated items, so
    ``reproduce.conditions=nominal,mass`` and ``reproduce.conditions=(nominal,)`` both work.
    """
    if is_dataclass(_current(cfg, path)):  # a section such as cell.peg: only its keys are set
        raise ConfigError(path, "is a group of keys, not one key (vgs config lists them)")
    if isinstance(value, str) and isinstance(_current(cfg, path), tuple):
        items = value.strip().strip("()[]").split(",")
        value = tuple(parse_value(item.strip()) for item in items if item.strip())
    try:
        return override(cfg, path, value)
    except ConfigError as exc:
        if exc.message == NO_SUCH_FIELD:
            raise ConfigError(exc.field, f"{NO_SUCH_FIELD} (vgs config lists them)") from None
        raise
    except (TypeError, ValueError) as exc:
        raise ConfigError(path, f"invalid value {value!r} ({exc})") from exc


def check_hole_fits(cfg: ExperimentConfig) -> None:
    """The hole (made for the nominal peg plus the clearance) must be wider than the peg, and
    deeper than the insertion depth K.

    Raises:
        ConfigError: ``hole.clearance`` or ``hole.depth`` otherwise.
    """
    hole, peg = cfg.cell.hole, cfg.cell.peg
    depth_k = cfg.assembly.insertion_depth
    if hole.depth <= depth_k:
        raise ConfigError("hole.depth", f"{hole.depth * 1000:g} mm must exceed the insertion "
                                        f"depth K = {depth_k * 1000:g} mm")
    if hole.diameter <= peg.diameter:
        raise ConfigError(
            "hole.clearance",
            f"the hole ({hole.diameter * 1000:g} mm = {hole.peg_diameter * 1000:g} mm + "
            f"{hole.clearance * 1000:g} mm clearance) must be wider than the peg "
            f"({peg.diameter * 1000:g} mm)",
        )


def config_from_args(args: argparse.Namespace) -> ExperimentConfig:
    """The profile with the override flags and ``--set`` pairs applied, checked.

    A command that reads only some sections of the configuration (``args.config_sections``,
    e.g. ``model-info``: ``network``) refuses ``--set`` keys outside them.
    """
    cfg = profile(args.profile)
    # The hole is made for the nominal peg: --peg-diameter changes the peg, not the hole.
    cfg = apply_override(cfg, "cell.hole.peg_diameter", PegConfig().diameter)
    for flag, path in OVERRIDE_FLAGS.items():
        value = getattr(args, flag, None)  # commands without the cell flags have none
        if value is not None:
            cfg = apply_override(cfg, path, value)
    sections = getattr(args, "config_sections", None)
    for pair in args.set:
        key, sep, text = pair.partition("=")
        key = key.strip()
        if not sep or not key:
            raise ConfigError("set", f"expected key=value, got {pair!r}")
        if sections and key.split(".")[0] not in sections:
            raise ConfigError("set", f"vgs {args.command} uses only the keys "
                                     f"{', '.join(f'{name}.*' for name in sections)}, not {key}")
        cfg = apply_override(cfg, key, parse_value(text.strip()))
    cfg = check_config(cfg)  # types (True is not a mass) and seeds
    check_hole_fits(cfg)
    return cfg


def seed_arg(text: str) -> int:
    """An argparse type: a seed is a non-negative integer."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a seed must be a non-negative integer, got "
                                         f"{text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"a seed must be a non-negative integer, got {value}")
    return value


def _float_list_mm(text: str) -> tuple[float, ...]:
    """Comma-separated millimetres -> metres."""
    try:
        values = tuple(float(v) / 1000.0 for v in text.split(",") if v.strip())
    except ValueError as exc:
        raise ConfigError("offsets", f"expected comma-separated numbers in mm, got {text!r}") \
            from exc
    if not values:
        raise ConfigError("offsets", "no offsets given")
    return values


# -- commands -----------------------------------------------------------------------------------


def cmd_demo(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """One traced episode: phase table (or JSON record), DIR/demo.png and, with ``--video``, the
    episode rendered as a video."""
    video_size = _video_size(args.video_size) if args.video else None
    if args.video:
        check_video_name(args.video)
        headless_gl_default()  # before anything imports mujoco
        from vgs.render import require_gl

        require_gl()  # before the episode, not after it
    from vgs.experiments.demo import format_report, run_demo
    from vgs.experiments.plots import demo_figure

    seed = cfg.seed if args.seed is None else args.seed
    result = run_demo(cfg, seed, args.offset / 1000.0)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    figure = demo_figure(result, out / "demo.png")
    video = None
    if args.video and video_size is not None:
        from vgs.experiments.demo import demo_video

        video = demo_video(result, cfg.cell, args.video, fps=args.video_fps,
                           speed=args.video_speed, width=video_size[0], height=video_size[1])
    if args.json:
        print(dumps(result.record.to_row()))
    else:
        print(format_report(result.record))
        print(f"\nfigure          {figure}")
        if video is not None:
            print(f"video           {video}")
    return 0


def check_video_name(name: str) -> None:
    """Raise :class:`ConfigError` (``video``) unless ``name`` ends in .mp4 or .gif."""
    if Path(name).suffix.lower() not in (".mp4", ".gif"):
        raise ConfigError("video", f"{name}: the file must end in .mp4 or .gif")


def headless_gl_default() -> None:
    """Let MuJoCo render headless (``MUJOCO_GL=egl``) where no display is set and the user
    chose no back end; must run before mujoco is first imported to take effect."""
    if "MUJOCO_GL" not in os.environ and not (os.environ.get("DISPLAY")
                                              or os.environ.get("WAYLAND_DISPLAY")):
        os.environ["MUJOCO_GL"] = "egl"


def _video_size(text: str) -> tuple[int, int]:
    """``WxH`` -> (width, height) in pixels."""
    w, sep, h = text.lower().partition("x")
    try:
        size = (int(w), int(h))
    except ValueError:
        size = (0, 0)
    if not sep or not (16 <= size[0] <= 1920 and 16 <= size[1] <= 1080):
        raise ConfigError("video-size", f"expected WxH within 16-1920 x 16-1080, got {text!r}")
    return size


def cmd_sweep(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Grasp-offset sweep: DIR/sweep.csv, DIR/sweep.png and DIR/summary.json."""
    from vgs.experiments.sweep import SweepSpec, default_offsets, sweep_to_folder

    if args.offsets_mm is not None:
        offsets = _float_list_mm(args.offsets_mm)
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
    from vgs.experiments.scene import export_scene

    info = export_scene(cfg, args.out, seed=args.seed)
    print(f"wrote {info.path} ({info.nbody} bodies, {info.ngeom} geoms, {info.nmesh} meshes, "
          f"{info.nu} actuators, cameras {', '.join(info.cameras)}); it opens at home with the "
          f"peg on the table (seed {args.seed}) and holds still until you act; open it with: "
          f"python -m mujoco.viewer --mjcf {info.path}  (Python: mujoco.MjModel.from_xml_path; "
          f"ctrl = 0 holds home, ctrl_i = q - q_home_i drives joint i to q)")
    return 0


def cmd_export_policy(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Write a training run's network as plain weights plus a JSON description."""
    from vgs.experiments.export_policy import export_policy

    written = export_policy(Path(args.run_dir), Path(args.out))
    print(f"wrote {written.weights} ({written.parameters} values; "
          f"torch.load(path, weights_only=True)) and {written.description}; the plain-torch "
          f"snippet that runs them: docs/grasping.md, 'Using a trained network without vgs'")
    if written.run_json is not None:
        print(f"and {written.run_json}: vgs evaluate --policy {written.weights.parent} loads "
              "the folder without the checkpoint")
    return 0


def flag_overrides(cfg: ExperimentConfig, args: argparse.Namespace,
                   fields: dict[str, str]) -> ExperimentConfig:
    """Apply the command's own flags (``{flag name: dotted config path}``) that were given."""
    for flag, path in fields.items():
        value = getattr(args, flag)
        if value is not None:
            cfg = apply_override(cfg, path, value)
    return cfg


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
                                     "device": "train.device"})
    out = train(cfg, args.mode, Path(args.out), progress=not args.no_progress)
    print(f"run in {out}: episodes.csv, tensorboard/, checkpoint.pt")
    return 0


def cmd_heatmap(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Q-value heat maps of a training run, untrained beside trained (paper Figure 7)."""
    from vgs.experiments.heatmap import plot_heatmaps

    out = plot_heatmaps(Path(args.run_dir), Path(args.out), scenes=args.scenes)
    print(f"wrote {out}")
    return 0


def cmd_curves(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Learning curves of runs and where each policy grasps; prints a summary table."""
    from vgs.experiments.curves import plot_curves

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


def cmd_evaluate(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Evaluate one policy on one condition: DIR/episodes.parquet, .csv and summary.json."""
    from vgs.experiments.evaluate import EvalSpec, evaluate, summarize

    episodes = cfg.eval.episodes if args.episodes is None else args.episodes
    spec = EvalSpec(args.policy, args.condition, episodes,
                    cfg.reproduce.eval_seed if args.seed is None else args.seed)
    df = evaluate(cfg, spec, Path(args.out), workers=args.workers, backend=args.backend,
                  ray_address=args.ray_address, progress=not args.no_progress)
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


def cmd_report(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Build DIR/report.md and DIR/report.html from the results in DIR."""
    from vgs.experiments.report import build_report

    path = build_report(Path(args.dir), **({"title": args.title} if args.title else {}))
    print(f"wrote {path} and {path.with_suffix('.html')}")
    if args.publish:
        from vgs.experiments.report import publish

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
    from vgs.experiments.seeds import seeds_report

    path = seeds_report([Path(d) for d in args.dirs], Path(args.out))
    print(path.read_text().split("![", 1)[0].rstrip())
    print(f"\nwrote {path}, {path.with_suffix('.csv')} and {path.with_suffix('.png')}")
    return 0


def cmd_status(args: argparse.Namespace, cfg: ExperimentConfig | None) -> int:
    """Print the progress of the jobs in a reproduce, train or evaluate folder."""
    from vgs.experiments.status import format_status

    print(format_status(Path(args.dir)))
    return 0


def cmd_config(args: argparse.Namespace, cfg: ExperimentConfig) -> int:
    """Print every settable key of the resolved configuration with its value and its doc."""
    from vgs.configdoc import format_settings, settings

    items = settings(cfg)
    if args.json:
        print(dumps([{"key": s.key, "value": s.value, "doc": s.doc} for s in items],
                    indent=2))
        return 0
    print(f"# profile {args.profile}, resolved; each key takes --set KEY=VALUE (a Python "
          "literal or text)")
    print(format_settings(items))
    return 0


# -- parser -------------------------------------------------------------------------------------


def _config_flags(p: argparse.ArgumentParser, sections: tuple[str, ...] = ()) -> None:
    """Give a command that builds its configuration from a profile ``--profile`` and ``--set``;
    with ``sections`` (the command reads only those) ``--set`` takes only their keys, without
    them the command also takes the cell's override flags (``--peg-mass`` ...)."""
    p.add_argument("--profile", default="paper",
                   help="configuration profile: smoke, quick, medium or paper "
                        "(default: paper; the cell is the same in all profiles)")
    group = p.add_argument_group("configuration overrides (SI units; vgs config lists every key)")
    if not sections:
        group.add_argument("--peg-mass", type=float, help="peg mass [kg] (cell.peg.mass)")
        group.add_argument("--peg-length", type=float, help="peg length [m] (cell.peg.length)")
        group.add_argument("--peg-diameter", type=float,
                           help="peg diameter [m] (cell.peg.diameter); the hole stays made for "
                                "the nominal 30 mm peg")
        group.add_argument("--clearance", type=float,
                           help="diametral clearance [m] (cell.hole.clearance)")
        group.add_argument("--hole-depth", type=float, help="hole depth [m] (cell.hole.depth)")
        group.add_argument("--gripper-force", type=float,
                           help="RG2 gripping force, 3-40 N (cell.gripper.force)")
    which = (" or ".join(f"{name}.*" for name in sections) + " field") if sections else "field"
    example = "network.num_rotations=8" if sections == ("network",) else "assembly.press_force=12"
    group.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help=f"any {which} by dotted path, e.g. --set {example} (repeatable; "
                            "the value is a Python literal or a string)")
    p.set_defaults(config_sections=sections)


def build_parser() -> argparse.ArgumentParser:
    """The ``vgs`` argument parser with its subcommands."""
    parser = _Parser(prog="vgs", description="Visual grasping strategy for peg-in-hole "
                                             "assembly (UR5 + RG2 in MuJoCo).")
    from vgs import __version__

    parser.add_argument("--version", action="version", version=f"vgs {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = sub.add_parser("demo", help="one whole episode with a figure")
    _config_flags(demo)
    demo.add_argument("--seed", type=seed_arg, help="episode seed (default: the profile's seed)")
    demo.add_argument("--json", action="store_true",
                      help="print only the episode record as JSON on stdout")
    demo.add_argument("--out", default="runs/demo",
                      help="folder of demo.png (default: %(default)s)")
    demo.add_argument("--offset", type=float, default=0.0, metavar="MM",
                      help="grasp offset from the visible peg centre along its axis [mm] "
                           "(default: 0, the centre heuristic)")
    demo.add_argument("--video", metavar="FILE",
                      help="also render the episode from the perspective camera to FILE (.mp4 "
                           "or .gif), phase and F/T reading on every frame; needs OpenGL "
                           "(headless: MUJOCO_GL=egl, the default without a display)")
    demo.add_argument("--video-fps", type=float, default=15.0,
                      help="video frames per second (default: %(default)s)")
    demo.add_argument("--video-speed", type=float, default=4.0,
                      help="simulated seconds per second of video (default: %(default)s)")
    demo.add_argument("--video-size", default="480x360", metavar="WxH",
                      help="frame size in pixels (default: %(default)s)")
    demo.set_defaults(func=cmd_demo)

    sweep = sub.add_parser("sweep", help="assembly time against the grasp offset")
    _config_flags(sweep)
    sweep.add_argument("--offsets", type=int, default=9,
                       help="number of offsets over +-(L/2 - 15 mm) (default: %(default)s)")
    sweep.add_argument("--offsets-mm", metavar="A,B,...",
                       help="explicit offsets [mm], comma-separated (overrides --offsets); write "
                            "--offsets-mm=-20,0,20 when the first is negative")
    sweep.add_argument("--trials", type=int, default=20, help="trials per offset")
    sweep.add_argument("--out", default="runs/sweep", help="output folder (default: %(default)s)")
    sweep.add_argument("--mass-range", type=float, default=0.0,
                       help="peg mass factor uniform in 1 +- this (default: 0)")
    sweep.add_argument("--length-range", type=float, default=0.0,
                       help="peg length factor uniform in 1 +- this; the mass follows the "
                            "volume (default: 0)")
    sweep.add_argument("--seed", type=seed_arg, help="root seed (default: the profile's seed)")
    sweep.add_argument("--workers", type=int,
                       help="worker processes (default: the number of CPU cores)")
    sweep.add_argument("--no-progress", action="store_true", help="no progress bar")
    sweep.set_defaults(func=cmd_sweep)

    scene = sub.add_parser("export-scene",
                           help="write the cell as MJCF, ready to open in MuJoCo's viewer")
    _config_flags(scene)
    scene.add_argument("--out", default="scene.xml", help="MJCF file (default: %(default)s)")
    scene.add_argument("--seed", type=seed_arg, default=0,
                       help="reset seed of the written default state: peg pose, hole position "
                            "(default: 0)")
    scene.set_defaults(func=cmd_export_scene)

    export_pol = sub.add_parser("export-policy",
                                help="a training run's network as plain weights (torch.load "
                                     "weights_only) plus a JSON description")
    export_pol.add_argument("run_dir", metavar="RUN", help="a training run folder")
    export_pol.add_argument("--out", required=True,
                            help="weights file (.pt); the description goes beside it (.json). "
                                 "A folder (no suffix) gets policy.pt, policy.json and run.json: "
                                 "a policy folder vgs evaluate --policy loads")
    export_pol.set_defaults(func=cmd_export_policy)

    info = sub.add_parser("model-info",
                          help="parameter counts and tensor shapes of the grasp network")
    _config_flags(info, sections=("network",))
    info.add_argument("--backbone", help="densenet121 or light (default: the profile's)")
    info.add_argument("--rotations", type=int, help="number of grasp rotations R")
    info.add_argument("--rotate", help="input or features (default: the profile's)")
    info.add_argument("--size", type=int, default=224, help="heightmap side [px]")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(func=cmd_model_info)

    train = sub.add_parser("train",
                           help="train the grasp policy (vgs or baseline); resumes from --out")
    _config_flags(train)
    train.add_argument("--mode", required=True, choices=("vgs", "baseline"),
                       help="vgs: grasp + assembly reward; baseline: grasp reward only")
    train.add_argument("--out", required=True, help="run folder (started again: resumes)")
    train.add_argument("--episodes", type=int, help="episodes in all (default: the profile's)")
    train.add_argument("--backbone", help="densenet121 or light (default: the profile's)")
    train.add_argument("--seed", type=seed_arg, help="root seed (default: the profile's)")
    train.add_argument("--device", help="cpu, cuda or auto (default: the profile's)")
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.set_defaults(func=cmd_train)

    heat = sub.add_parser("heatmap", help="Q heat maps of a run, untrained beside trained "
                                          "(Fig. 7), with the run's own configuration")
    heat.add_argument("run_dir", help="a training run folder")
    heat.add_argument("--out", required=True, help="figure file (PNG)")
    heat.add_argument("--scenes", type=int, default=2, help="scenes, one per row")
    heat.set_defaults(func=cmd_heatmap)

    curves = sub.add_parser("curves",
                            help="learning curves of runs and where each policy grasps")
    curves.add_argument("runs", nargs="+", help="training run folders")
    curves.add_argument("--out", required=True, help="figure file (PNG)")
    curves.add_argument("--window", type=int, default=20, help="moving-mean window [episodes]")
    curves.add_argument("--json", action="store_true", help="print the summary as JSON")
    curves.set_defaults(func=cmd_curves)

    evaluate = sub.add_parser("evaluate",
                              help="test one policy on one condition (parallel, resumable)")
    _config_flags(evaluate)
    evaluate.add_argument("--policy", required=True,
                          help="a training run folder, random, center, or module:function")
    evaluate.add_argument("--condition", default="nominal", choices=("nominal", "mass", "length"),
                          help="nominal peg, mass +-15 %%, or length 85-115 %% with the mass "
                               "following (default: %(default)s)")
    evaluate.add_argument("--episodes", type=int,
                          help="test episodes (default: the profile's eval.episodes)")
    evaluate.add_argument("--seed", type=seed_arg,
                          help="root seed of the test scenes (default: reproduce.eval_seed)")
    _parallel_flags(evaluate)
    evaluate.add_argument("--out", required=True, help="output folder (started again: resumes)")
    evaluate.add_argument("--json", action="store_true", help="print the summary as JSON")
    evaluate.set_defaults(func=cmd_evaluate)

    repro = sub.add_parser("reproduce",
                           help="the paper's experiments: train, evaluate, sweep, report")
    _config_flags(repro)
    repro.add_argument("--out", required=True, help="output folder (started again: resumes)")
    repro.add_argument("--stages", default="train,evaluate,sweep,report",
                       help="comma-separated stages to run, in pipeline order whatever the "
                            "order given (default: %(default)s)")
    _parallel_flags(repro)
    repro.set_defaults(func=cmd_reproduce)

    report = sub.add_parser("report",
                            help="write DIR/report.md and DIR/report.html from DIR's results")
    report.add_argument("dir", help="a reproduce folder (with eval/<policy>/<condition>/)")
    report.add_argument("--publish", metavar="DEST",
                        help="also copy the small result files (report, figures, tables; no "
                             "checkpoints) and each finished run's final network "
                             "(DEST/<mode>/policy.pt) to DEST, e.g. docs/results/quick")
    report.add_argument("--title", help="the report's title (default: VGS reproduction report)")
    report.set_defaults(func=cmd_report)

    seeds = sub.add_parser("seeds", help="VGS against the baseline per training seed and on "
                                         "average, from several results folders")
    seeds.add_argument("dirs", nargs="+", metavar="DIR",
                       help="reproduce folders or their published copies (docs/results/...), "
                            "each with eval/<policy>/<condition>/episodes.parquet")
    seeds.add_argument("--out", required=True,
                       help="folder of seeds.md, seeds.csv and seeds.png")
    seeds.set_defaults(func=cmd_seeds)

    status = sub.add_parser("status", help="how far a reproduction, training run or evaluation "
                                           "folder has got (safe while it runs)")
    status.add_argument("dir", help="a reproduce, train or evaluate output folder")
    status.set_defaults(func=cmd_status)

    config = sub.add_parser("config", help="the resolved configuration: every key --set takes, "
                                           "its value and what it means")
    _config_flags(config)
    config.add_argument("--json", action="store_true",
                        help="print a JSON list of {key, value, doc} with each doc whole")
    config.set_defaults(func=cmd_config)
    return parser


def _parallel_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--workers", type=int,
                   help="parallel worker processes (default: the number of CPU cores)")
    p.add_argument("--backend", default="local", choices=("local", "ray"),
                   help="local processes or Ray (pip install 'vgs[ray]') (default: local)")
    p.add_argument("--ray-address", help="address of a running Ray cluster (default: start a "
                                         "local one)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``vgs`` command; return its exit code.

    Args:
        argv: Arguments without the program name (default: ``sys.argv[1:]``).
    """
    args = None
    try:
        args, extra = build_parser().parse_known_args(argv)
        if extra:  # a flag another command takes, or one no command does
            raise UsageError(f"{args.command}: does not take {' '.join(extra)} (vgs "
                             f"{args.command} --help lists what it takes)")
        cfg = config_from_args(args) if hasattr(args, "profile") else None
        return args.func(args, cfg)
    except VGSError as exc:
        return _error(str(exc))
    except OSError as exc:
        if isinstance(exc, BrokenPipeError):
            # The reader of stdout went away (e.g. `vgs model-info | head`): stop quietly.
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 1
        # A file or folder the command cannot use: an --out that is a file, a full disk, no
        # permission. The run's files are as the last completed write left them.
        where = f"{exc.filename}: " if exc.filename else ""
        return _error(f"{where}{exc.strerror or exc}")
    except KeyboardInterrupt:
        command = getattr(args, "command", None)
        again = ("; run the same command again to resume (finished episodes are kept)"
                 if command in RESUMABLE else "")
        print(f"vgs: interrupted{again}", file=sys.stderr)
        return 130


RESUMABLE = ("train", "evaluate", "reproduce")


def _error(message: str) -> int:
    message = " ".join(message.split())
    print(f"vgs: error: {message}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main())
