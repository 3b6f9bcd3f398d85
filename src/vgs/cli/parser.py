"""The parser of the ``vgs`` command, one sub-parser a command with only the flags it uses, and
:func:`main`: one-line errors with exit code 2, Ctrl-C with exit code 130."""

from __future__ import annotations

import argparse
import os
import re
import signal
import sys
import threading
from collections.abc import Sequence
from typing import Any

from vgs.cli.folders import (
    cmd_com_fit,
    cmd_curves,
    cmd_export_policy,
    cmd_grasp_sites,
    cmd_heatmap,
    cmd_report,
    cmd_seeds,
    cmd_status,
)
from vgs.cli.options import (
    CommandParser,
    UsageError,
    check_flag_bounds,
    config_from_args,
    seed_arg,
)
from vgs.cli.runs import (
    cmd_config,
    cmd_demo,
    cmd_evaluate,
    cmd_export_scene,
    cmd_model_info,
    cmd_reproduce,
    cmd_sweep,
    cmd_train,
)
from vgs.config import CONDITIONS
from vgs.errors import InterruptedBySignal, VGSError


def _config_flags(p: argparse.ArgumentParser, sections: tuple[str, ...] = ()) -> None:
    """Give a command that builds its configuration from a profile ``--profile`` (or a file,
    ``--config``) and ``--set``;
    with ``sections`` (the command reads only those) ``--set`` takes only their keys, without
    them the command also takes the cell's override flags (``--peg-mass`` ...)."""
    p.add_argument("--profile",
                   help="configuration profile: smoke, quick, medium, paper or paper-light "
                        "(the paper's protocol sized for a 2-core CPU; docs/training.md) "
                        "(default: paper; the cell is the same in all profiles)")
    p.add_argument("--config", metavar="FILE",
                   help="the whole configuration from FILE instead of a profile: JSON as vgs "
                        "config --json prints it, a TOML or JSON table of sections, or a run "
                        "folder's metadata (run.json, meta.json, sweep.json, reproduce.json; "
                        "or the folder itself); not with --profile; --set and the flags "
                        "below still apply on top")
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
    parser = CommandParser(prog="vgs", description="Visual grasping strategy for peg-in-hole "
                                             "assembly (UR5 + RG2 in MuJoCo).")
    parser.add_argument("--version", action=_Version, nargs=0,
                        help="print vgs's version and the source revision it runs from "
                             "(a checkout's commit or the one its wheel was built from)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_demo(sub)
    _add_sweep(sub)
    _add_export_scene(sub)
    _add_export_policy(sub)
    _add_model_info(sub)
    _add_train(sub)
    _add_heatmap(sub)
    _add_curves(sub)
    _add_evaluate(sub)
    _add_reproduce(sub)
    _add_report(sub)
    _add_seeds(sub)
    _add_grasp_sites(sub)
    _add_com_fit(sub)
    _add_status(sub)
    _add_config(sub)
    return parser


class _Version(argparse.Action):
    """``--version``: ``vgs 0.1.0 (source <commit>)``, the revision found only when asked."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        from vgs import __version__
        from vgs.revision import source_revision

        print(f"vgs {__version__} (source {source_revision()})")
        parser.exit()


def _add_demo(sub: Any) -> None:
    """``vgs demo``."""
    demo = sub.add_parser("demo", help="one whole episode with a figure")
    _config_flags(demo)
    demo.add_argument("--seed", type=seed_arg, help="episode seed (default: the profile's seed)")
    demo.add_argument("--json", action="store_true",
                      help="print only the episode record as JSON on stdout")
    demo.add_argument("--out", default="runs/demo",
                      help="folder of demo.png (default: %(default)s)")
    demo.add_argument("--force", action="store_true",
                      help="overwrite an existing OUT/demo.png, --video, --trace or --rerun "
                           "file (without it the demo refuses, before running the episode)")
    demo.add_argument("--no-progress", action="store_true",
                      help="no progress lines on stderr during the episode")
    demo.add_argument("--offset", type=float, default=0.0, metavar="MM",
                      help="grasp offset from the visible peg centre along its axis [mm] "
                           "(default: 0, the centre heuristic)")
    demo.add_argument("--policy", metavar="POLICY",
                      help="grasp with this policy instead: a training run or policy folder "
                           "(its Q heat map beside the video and in the figure), random, center, "
                           "com-oracle (the peg's true centre of mass, analysis only) or "
                           "module:function, choosing as vgs evaluate does")
    demo.add_argument("--condition", default="nominal", choices=CONDITIONS,
                      help="the episode's peg: a test condition's, at the far end of its range "
                           "(mass and length +15 %%, com-spread 20 mm; default: %(default)s)")
    demo.add_argument("--video", metavar="FILE",
                      help="also render the episode from --camera to FILE (.mp4 or .gif), "
                           "phase and F/T reading on every frame; needs OpenGL (headless: "
                           "MUJOCO_GL=egl, the default without a display)")
    _camera_flag(demo)
    demo.add_argument("--video-fps", type=float, default=15.0,
                      help="video frames per second (default: %(default)s)")
    demo.add_argument("--video-speed", type=float, default=4.0,
                      help="simulated seconds per second of video (default: %(default)s)")
    demo.add_argument("--video-size", default="480x360", metavar="WxH",
                      help="frame size in pixels (default: %(default)s)")
    demo.add_argument("--trace", metavar="FILE",
                      help="also write the episode's per-tick trace to FILE (.parquet): time, "
                           "phase, TCP pose, tared F/T, joints, finger width, ground truth "
                           "(docs/columns.md)")
    demo.add_argument("--rerun", metavar="FILE",
                      help="also write the episode as a Rerun recording to FILE (.rrd): "
                           "heightmap, grasp, Q map, TCP, peg and hole, F/T and phase over time "
                           "(needs the rerun extra)")
    demo.set_defaults(func=cmd_demo)


def _camera_flag(parser: Any) -> None:
    """``--camera`` of the videos (vgs.render.VIDEO_CAMERAS, named here so that the parser
    imports no MuJoCo)."""
    parser.add_argument("--camera", default="perspective", choices=("perspective", "hole"),
                        help="the video's camera: the robot and its workspace, or a close-up "
                             "of the hole (default: %(default)s)")


def _add_sweep(sub: Any) -> None:
    """``vgs sweep``."""
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


def _add_export_scene(sub: Any) -> None:
    """``vgs export-scene``."""
    scene = sub.add_parser("export-scene",
                           help="write the cell as MJCF, ready to open in MuJoCo's viewer")
    _config_flags(scene)
    scene.add_argument("--out", default="scene.xml", help="MJCF file (default: %(default)s)")
    scene.add_argument("--seed", type=seed_arg, default=0,
                       help="reset seed of the written default state: peg pose, hole position "
                            "(default: 0)")
    scene.set_defaults(func=cmd_export_scene)


def _add_export_policy(sub: Any) -> None:
    """``vgs export-policy``."""
    export_pol = sub.add_parser("export-policy",
                                help="a training run's network as plain weights (torch.load "
                                     "weights_only) plus a JSON description")
    export_pol.add_argument("run_dir", metavar="RUN", help="a training run folder")
    export_pol.add_argument("--out", required=True,
                            help="weights file (.pt); the description goes beside it (.json). "
                                 "A folder (no suffix) gets policy.pt, policy.json and run.json: "
                                 "a policy folder vgs evaluate --policy loads")
    export_pol.set_defaults(func=cmd_export_policy)


def _add_model_info(sub: Any) -> None:
    """``vgs model-info``."""
    info = sub.add_parser("model-info",
                          help="parameter counts and tensor shapes of the grasp network")
    _config_flags(info, sections=("network",))
    info.add_argument("--backbone", help="densenet121 or light (default: the profile's)")
    info.add_argument("--rotations", type=int, help="number of grasp rotations R")
    info.add_argument("--rotate", help="input, features or none (default: the profile's)")
    info.add_argument("--size", type=int, default=224, help="heightmap side [px]")
    info.add_argument("--json", action="store_true", help="print JSON")
    info.set_defaults(func=cmd_model_info)


def _add_train(sub: Any) -> None:
    """``vgs train``."""
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
    train.add_argument("--workers", type=int, metavar="K",
                       help="episodes whose physics runs side by side in K processes: sets "
                            "train.parallel_episodes (the grasps of K consecutive episodes "
                            "chosen by the same network; default: the profile's, 1 = the "
                            "paper's order)")
    _backend_flags(train, "where the physics of parallel episodes (train.parallel_episodes > 1) "
                          "runs: ")
    train.add_argument("--no-progress", action="store_true", help="no progress bar")
    train.set_defaults(func=cmd_train)


def _add_heatmap(sub: Any) -> None:
    """``vgs heatmap``."""
    heat = sub.add_parser("heatmap", help="Q heat maps of a run, untrained beside trained "
                                          "(Fig. 7), with the run's own configuration")
    heat.add_argument("run_dir", help="a training run folder")
    heat.add_argument("--out", required=True, help="figure file (PNG)")
    heat.add_argument("--scenes", type=int, default=2, help="scenes, one per row")
    heat.set_defaults(func=cmd_heatmap)


def _add_curves(sub: Any) -> None:
    """``vgs curves``."""
    curves = sub.add_parser("curves",
                            help="learning curves of runs and where each policy grasps")
    curves.add_argument("runs", nargs="+", help="training run folders")
    curves.add_argument("--out", required=True, help="figure file (PNG)")
    curves.add_argument("--window", type=int, default=20, help="moving-mean window [episodes]")
    curves.add_argument("--json", action="store_true", help="print the summary as JSON")
    curves.set_defaults(func=cmd_curves)


def _add_evaluate(sub: Any) -> None:
    """``vgs evaluate``."""
    evaluate = sub.add_parser("evaluate",
                              help="test one policy on one condition (parallel, resumable)")
    _config_flags(evaluate)
    evaluate.add_argument("--policy", required=True,
                          help="a training run folder, random, center, com-oracle (grasps at "
                               "the peg's true centre of mass: ground truth, analysis only) or "
                               "module:function")
    evaluate.add_argument("--condition", default="nominal", choices=CONDITIONS,
                          help="nominal peg, mass +-15 %%, length 85-115 %% with the mass "
                               "following, or a centre of mass off the middle: com (heavy end "
                               "painted), com-hidden, com-spread (default: %(default)s)")
    evaluate.add_argument("--episodes", type=int,
                          help="test episodes (default: the profile's eval.episodes)")
    evaluate.add_argument("--seed", type=seed_arg,
                          help="root seed of the test scenes (default: reproduce.eval_seed)")
    _parallel_flags(evaluate)
    evaluate.add_argument("--out", required=True, help="output folder (started again: resumes)")
    evaluate.add_argument("--json", action="store_true", help="print the summary as JSON")
    evaluate.add_argument("--videos", type=int, default=0, metavar="N",
                          help="afterwards, run the first N test episodes again by their seeds "
                               "and render them to OUT/videos/ (the policy's Q map beside; "
                               "needs OpenGL) (default: 0)")
    evaluate.add_argument("--traces", type=int, default=0, metavar="N",
                          help="afterwards, run the first N test episodes again by their seeds "
                               "and write their per-tick traces to OUT/traces/ (default: 0)")
    _camera_flag(evaluate)
    evaluate.set_defaults(func=cmd_evaluate)


def _add_reproduce(sub: Any) -> None:
    """``vgs reproduce``."""
    repro = sub.add_parser("reproduce",
                           help="the paper's experiments: train, evaluate, sweep, report")
    _config_flags(repro)
    repro.add_argument("--out", required=True, help="output folder (started again: resumes)")
    repro.add_argument("--stages", default="train,evaluate,sweep,report",
                       help="comma-separated stages to run, in pipeline order whatever the "
                            "order given (default: %(default)s)")
    _parallel_flags(repro)
    repro.set_defaults(func=cmd_reproduce)


def _add_report(sub: Any) -> None:
    """``vgs report``."""
    report = sub.add_parser("report",
                            help="write DIR/report.md and DIR/report.html from DIR's results")
    report.add_argument("dir", help="a reproduce folder (with eval/<policy>/<condition>/)")
    report.add_argument("--publish", metavar="DEST",
                        help="also copy the small result files (report, figures, tables; no "
                             "checkpoints) and each finished run's final network "
                             "(DEST/<mode>/policy.pt) to DEST, e.g. docs/results/quick")
    report.add_argument("--title", help="the report's title (default: VGS reproduction report)")
    report.add_argument("--center", metavar="DIR",
                        help="a results folder with the centre heuristic's tests on the same "
                             "scenes (e.g. docs/results/paper_center_stiction), for VGS's regret "
                             "against it when DIR has none")
    report.set_defaults(func=cmd_report)


def _add_seeds(sub: Any) -> None:
    """``vgs seeds``."""
    seeds = sub.add_parser("seeds", help="VGS against the baseline per training seed and on "
                                         "average, from several results folders")
    seeds.add_argument("dirs", nargs="+", metavar="DIR",
                       help="reproduce folders or their published copies (docs/results/...), "
                            "each with eval/<policy>/<condition>/episodes.parquet")
    seeds.add_argument("--out", required=True,
                       help="folder of seeds.md, seeds.csv, seeds.png and profile.png")
    seeds.add_argument("--center", metavar="DIR",
                       help="a results folder with the centre heuristic's tests on the same "
                            "scenes (e.g. docs/results/paper_center_stiction): VGS's regret "
                            "against it, P(VGS faster than the centre), its performance profile")
    seeds.set_defaults(func=cmd_seeds)


def _add_grasp_sites(sub: Any) -> None:
    """``vgs grasp-sites``."""
    sites = sub.add_parser("grasp-sites", help="where on the peg each test grasp lay, along "
                                               "its axis and across it, and what assembled")
    sites.add_argument("dir", help="a reproduce folder or its published copy (with "
                                   "reproduce.json and eval/<policy>/<condition>/)")
    sites.add_argument("--policy", action="append", metavar="LABEL",
                       help="only this policy's tests, e.g. baseline (repeatable; default all)")
    sites.add_argument("--condition", action="append", choices=CONDITIONS,
                       help="only this condition's tests (repeatable; default all)")
    sites.add_argument("--csv", metavar="FILE", help="also write one row per test episode "
                                                     "(along_mm, across_mm) to FILE")
    sites.add_argument("--workers", type=int, metavar="N",
                       help="processes that reset the test scenes (default: the number of CPU "
                            "cores); the table is the same for any number")
    sites.add_argument("--no-progress", action="store_true", help="no progress bar")
    sites.set_defaults(func=cmd_grasp_sites)


def _add_com_fit(sub: Any) -> None:
    """``vgs com-fit``."""
    fit = sub.add_parser("com-fit", help="does a shifted-mass sweep's time follow the grasp's "
                                         "distance from the centre of mass or from the middle")
    fit.add_argument("dir", help="a vgs sweep folder of a peg with peg.com_shift_mm > 0")
    fit.add_argument("--twin", help="the same sweep (scenes, offsets) of the uniform peg")
    fit.add_argument("--out", help="also write com_fit.md and com_fit.json here")
    fit.set_defaults(func=cmd_com_fit)


def _add_status(sub: Any) -> None:
    """``vgs status``."""
    status = sub.add_parser("status", help="how far a reproduction, training run or evaluation "
                                           "folder has got (safe while it runs)")
    status.add_argument("dir", help="a reproduce, train or evaluate output folder")
    status.set_defaults(func=cmd_status)


def _add_config(sub: Any) -> None:
    """``vgs config``."""
    config = sub.add_parser("config", help="the resolved configuration: every key --set takes, "
                                           "its value and what it means")
    _config_flags(config)
    config.add_argument("--json", action="store_true",
                        help="print a JSON list of {key, value, doc} with each doc whole")
    config.set_defaults(func=cmd_config)


def _parallel_flags(p: argparse.ArgumentParser) -> None:
    p.add_argument("--workers", type=int,
                   help="parallel worker processes (default: the number of CPU cores)")
    _backend_flags(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bars")


def _backend_flags(p: argparse.ArgumentParser, what: str = "") -> None:
    p.add_argument("--backend", default="local", choices=("local", "ray"),
                   help=what + "local processes or Ray (pip install 'vgs[ray]') "
                               "(default: local)")
    p.add_argument("--ray-address", help="address of a running Ray cluster (default: start a "
                                         "local one)")


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``vgs`` command; return its exit code.

    The first SIGINT, SIGTERM or SIGHUP stops the command (one line, exit code 130, 143 or
    129); every later one is ignored while it shuts down. Called from the command line
    (``argv`` None) an interrupted command keeps ignoring them until the process exits, so a
    second signal cannot end it by the signal or with a traceback; called with ``argv`` (in
    another program) the handlers it replaced are restored on return.

    Args:
        argv: Arguments without the program name (default: ``sys.argv[1:]``).
    """
    args = None
    interrupted = False
    handlers = _catch_termination()
    try:
        args, extra = build_parser().parse_known_args(argv)
        if extra:  # a flag another command takes, or one no command does
            raise UsageError(f"{args.command}: does not take {' '.join(extra)} (vgs "
                             f"{args.command} --help lists what it takes)")
        check_paths(args)  # before any work
        check_flag_bounds(args)
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
        # (a write to an open file names none: the folder the command writes into is named)
        path = exc.filename or getattr(args, "out", None) or getattr(args, "publish", None)
        where = f"{path}: " if path else ""
        return _error(f"{where}{exc.strerror or exc}")
    except KeyboardInterrupt as exc:
        interrupted = True
        _ignore_signals()  # one line, however often it is pressed (the handler did it already)
        command = getattr(args, "command", None)
        again = ("; run the same command again to resume (finished episodes are kept)"
                 if command in RESUMABLE else "")
        if isinstance(exc, InterruptedBySignal):
            print(f"vgs: stopped by {signal.Signals(exc.signum).name}{again}", file=sys.stderr)
            return 128 + exc.signum
        print(f"vgs: interrupted{again}", file=sys.stderr)
        return 130
    finally:
        if argv is not None or not interrupted:
            for signum, handler in handlers.items():
                signal.signal(signum, handler)


STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def _ignore_signals() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP (in the main thread; elsewhere nothing changes)."""
    if threading.current_thread() is threading.main_thread():
        for signum in STOP_SIGNALS:
            signal.signal(signum, signal.SIG_IGN)


def _catch_termination() -> dict[int, Any]:
    """Handle SIGTERM and SIGHUP like Ctrl-C (:class:`vgs.errors.InterruptedBySignal`): the
    command stops its workers and ends with one line and exit code 128 + signal (143 for
    SIGTERM). The first of SIGINT, SIGTERM and SIGHUP stops the command and makes every later
    one ignored (a second Ctrl-C during the shutdown changes nothing). Returns the handlers it
    replaced (none outside the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        return {}

    def stop(signum: int, frame: Any) -> None:
        _ignore_signals()  # the first signal stops, later ones wait
        if signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise InterruptedBySignal(signum)

    old = {}
    for signum in STOP_SIGNALS:
        old[signum] = signal.signal(signum, stop)
    return old


_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
_PATH_ARGS = ("out", "publish", "dir", "run_dir", "runs", "dirs")


def check_paths(args: argparse.Namespace) -> None:
    """Refuse empty, URI-like (``file:/x``, ``s3://b``) and non-UTF-8 paths before any work: an
    empty ``--out`` would write into the current folder, a URI-like one is taken as a URL by the
    table writers, and a name that is not UTF-8 fails only when the tables are written.

    Raises:
        UsageError: Naming the argument.
    """
    for name in _PATH_ARGS:
        value = getattr(args, name, None)
        for item in value if isinstance(value, list) else [value]:
            if not isinstance(item, str):
                continue
            flag = f"--{name.replace('_', '-')}" if name in ("out", "publish") else name.upper()
            if not item.strip():
                raise UsageError(f"{flag}: is empty; name a folder or file")
            try:
                item.encode("utf-8")
            except UnicodeEncodeError:
                raise UsageError(f"{flag}: {item.encode('utf-8', 'surrogateescape')!r} is not "
                                 "UTF-8; use a name in UTF-8") from None
            if _SCHEME.match(item):
                raise UsageError(f"{flag}: {item!r} looks like a URI; give a local path (a "
                                 "first component without ':')")
            if "\0" in item:
                raise UsageError(f"{flag}: holds a NUL character")


RESUMABLE = ("train", "evaluate", "reproduce", "sweep")


def _error(message: str) -> int:
    message = " ".join(message.split())
    print(f"vgs: error: {message}", file=sys.stderr)
    return 2
