"""Options and helpers shared by several subcommands."""

from __future__ import annotations

import argparse
import math

import numpy as np

from ..robot.tasks import TASKS
from ..support.reading import decimal

#: Where an option is added: a parser or one of its argument groups (both take add_argument).
Options = argparse._ActionsContainer

#: The positional ROBOT of the commands that take a built-in robot or a spec (not a bare URDF).
ROBOT_HELP = "built-in robot name or path of a robot spec (.toml)"


def add_robot_argument(parser: Options) -> None:
    """ROBOT: the positional of a command that takes a built-in robot or a spec (not a bare URDF)."""
    parser.add_argument("robot", help=ROBOT_HELP)


def add_guided_command(sub, name: str, summary: str, description: str, guide: str) -> argparse.ArgumentParser:
    """A subcommand's parser whose ``--help`` ends with ``guide`` (file formats, examples) printed
    as written, line breaks kept."""
    return sub.add_parser(
        name,
        help=summary,
        description=description,
        epilog=guide,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )


def add_configuration_command(sub, name: str, summary: str) -> argparse.ArgumentParser:
    """A subcommand's parser about one configuration of a robot: which robot and where it stands
    (:func:`add_robot_options`), what is computed there (:func:`add_analysis_options`) and on
    what floor (:func:`add_floor_options`)."""
    parser = sub.add_parser(name, help=summary)
    add_robot_options(parser)
    add_analysis_options(parser)
    add_floor_options(parser)
    return parser


def configuration_from_command(args) -> tuple:
    """For a command of :func:`add_configuration_command`: (the robot with its analysis options
    applied, its configuration, the keywords of :func:`mobmanip.analysis.single.analyze` the
    options give: ``object_mass``, ``decoupled``, ``measures`` and ``constraints``)."""
    robot, q = load_robot_and_configuration(args)
    robot = apply_analysis_options(robot, args)
    options = {
        "object_mass": args.object_mass,
        "decoupled": args.decoupled,
        "measures": requested_measures(args),
        "constraints": constraints_from_args(args),
    }
    return robot, q, options


def add_json_option(parser: Options, what: str) -> None:
    """--json OUT.json: write ``what`` (e.g. "the result") as JSON."""
    parser.add_argument("--json", metavar="OUT.json", help=f"write {what} as JSON")


def add_out_dir_option(parser: Options, files: str) -> None:
    """--out DIR: the folder the command writes ``files`` (e.g. "a.csv, a.json") to."""
    parser.add_argument("--out", metavar="DIR", help=f"write {files}")


def add_task_option(parser: Options) -> None:
    """--task NAME: one of the task spaces, else the spec's default."""
    parser.add_argument("--task", choices=list(TASKS), help="task space (default: the spec's default_task)")


def add_object_mass_option(parser: Options) -> None:
    """--object-mass KG: the held object's mass instead of the spec's."""
    parser.add_argument("--object-mass", type=decimal, metavar="KG", help="mass of the held object (default: spec)")


def add_urdf_options(parser: argparse.ArgumentParser, ee_required: bool = False) -> None:
    """--ee FRAME (repeatable) and --wheels RIGHT,LEFT, for a robot inferred from a URDF."""
    parser.add_argument(
        "--ee",
        action="append",
        metavar="FRAME",
        required=ee_required,
        help="end-effector frame of an arm (repeat for each arm, arm 1 first)",
    )
    parser.add_argument(
        "--wheels", metavar="RIGHT,LEFT", help="the drive-wheel joints, right then left (default: detected)"
    )


def add_robot_options(parser: argparse.ArgumentParser) -> None:
    """ROBOT or --urdf PATH --ee FRAME [--ee FRAME ...] [--wheels RIGHT,LEFT], then --q and --task."""
    parser.add_argument(
        "robot",
        nargs="?",
        help="built-in robot name (e.g. planar_dual_arm) or path of a robot spec (.toml); or use --urdf",
    )
    parser.add_argument("--urdf", metavar="PATH", help="a URDF to analyse without a spec (needs --ee)")
    add_urdf_options(parser)
    parser.add_argument(
        "--q", metavar="Q.json", help='configuration {"platform": [x, y, yaw], "joints": {NAME: value}}'
    )
    add_posture_option(parser, "the configuration: a named posture of the spec, platform at the origin")
    add_task_option(parser)
    add_strict_option(parser)
    add_description_options(parser)


def add_description_options(parser: argparse.ArgumentParser) -> None:
    """--xacro-arg NAME=VALUE and --package-path DIR (both repeatable): how a robot file is read."""
    parser.add_argument(
        "--xacro-arg",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="a xacro file's $(arg NAME) value (repeat for several; a spec may hold them in [xacro_args])",
    )
    parser.add_argument(
        "--package-path",
        action="append",
        default=[],
        metavar="DIR",
        help="a folder where $(find PKG) and package://PKG look for packages, before ROS_PACKAGE_PATH "
        "(repeat for several; a spec may list them in package_paths)",
    )


def read_options_from_args(args) -> dict:
    """The ``xacro_args`` and ``package_paths`` the command line gives (empty when none).

    Raises:
        UsageError: a --xacro-arg that is not NAME=VALUE.
    """
    from pathlib import Path

    from ..errors import UsageError

    arguments = {}
    for item in getattr(args, "xacro_arg", None) or ():
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise UsageError(f"--xacro-arg takes NAME=VALUE, got {item!r}")
        arguments[name.strip()] = value
    paths = tuple(Path(p).expanduser().resolve() for p in getattr(args, "package_path", None) or ())
    return {"xacro_args": arguments, "package_paths": paths}


def add_strict_option(parser: argparse.ArgumentParser) -> None:
    """--strict: refuse the robot file's flaws instead of repairing them."""
    parser.add_argument(
        "--strict",
        action="store_true",
        help="refuse a robot file's flaws (e.g. an inertia no rigid body can have) instead of repairing them "
        "with a warning (a spec may say strict = true)",
    )


def add_posture_option(parser: Options, what: str, default: str = "home") -> None:
    """--posture NAME: home, hold or a [postures.NAME] of the spec; ``default`` says which is
    taken without it."""
    parser.add_argument(
        "--posture",
        metavar="NAME",
        help=f"{what} (home, hold, or any [postures.NAME] of the spec; default: {default})",
    )


def robot_spec_from_args(args):
    """The spec named on the command line: ROBOT, or one inferred from --urdf and --ee.

    Raises:
        UsageError: neither or both of ROBOT and --urdf, --urdf without --ee, or --ee/--wheels
            without --urdf.
    """
    import dataclasses

    from ..errors import UsageError
    from ..robot.detect import parse_wheel_list, spec_from_urdf
    from ..robot.spec import find_spec

    urdf, ee, wheels = getattr(args, "urdf", None), getattr(args, "ee", None), getattr(args, "wheels", None)
    if args.robot is not None and urdf is not None:
        raise UsageError(f"give either ROBOT ({args.robot}) or --urdf ({urdf}), not both")
    if args.robot is None and urdf is None:
        raise UsageError("give a ROBOT (built-in name or spec .toml) or --urdf PATH --ee FRAME")
    options = read_options_from_args(args)
    if urdf is None:
        if ee or wheels:
            raise UsageError("--ee and --wheels go with --urdf; a ROBOT spec names its own end effectors and wheels")
        spec = find_spec(args.robot)
        if options["xacro_args"] or options["package_paths"]:
            spec = dataclasses.replace(
                spec,
                xacro_args={**spec.xacro_args, **options["xacro_args"]},
                package_paths=spec.package_paths + options["package_paths"],
            )
        return strict_if_asked(spec, args)
    if not ee:
        raise UsageError(f"--urdf {urdf} needs at least one --ee FRAME (the end effector of each arm)")
    wheel_list = None if wheels is None else parse_wheel_list(wheels)
    return strict_if_asked(spec_from_urdf(urdf, ee, wheels=wheel_list, read_options=options), args)


def strict_if_asked(spec, args):
    """The spec, made strict when the command line says --strict."""
    import dataclasses

    if not getattr(args, "strict", False):
        return spec
    return dataclasses.replace(spec, strict=True, accepted_repairs=())


def load_robot_and_configuration(args):
    """The robot named on the command line and its configuration (home pose without --q)."""
    from ..errors import MissingLimitError
    from ..robot.model import load_robot

    spec = robot_spec_from_args(args)
    try:
        robot = load_robot(spec)
    except MissingLimitError as exc:
        if getattr(args, "urdf", None) is None:
            raise
        hint = f"{exc.source} (with --urdf there is no spec yet: `mobmanip init-spec {args.urdf} --ee ...` writes one)"
        raise MissingLimitError(exc.name, exc.kind, hint) from None
    return robot, configuration_from_args(robot, args)


def configuration_from_args(robot, args):
    """The configuration --q or --posture names (the home configuration without either).

    Raises:
        UsageError: both --q and --posture.
        UnknownPostureError: a posture the spec does not define (the message lists them).
    """
    from ..errors import UsageError
    from ..postures.named import named_configuration
    from ..robot.configurations import read_configuration

    q_file, posture = getattr(args, "q", None), getattr(args, "posture", None)
    if q_file and posture:
        raise UsageError(f"give either --q ({q_file}) or --posture ({posture}), not both")
    if q_file:
        return read_configuration(robot, q_file)
    return named_configuration(robot, posture or "home")


def print_path_warnings(path, step: float) -> None:
    """An object path's ends at which the object still moves (:meth:`ObjectPath.moving_ends`),
    one warning line each on standard error, once the motion has been planned."""
    import sys

    from ..support.notices import notice

    for text in path.moving_ends(step):
        notice(text, stream=sys.stderr)


def print_warnings(analysis, stream=None) -> None:
    """The analysis's warnings, one line each, on standard error (each once per command: a
    repair already reported when the robot was loaded is not repeated). A measure that ignores a
    constraint is marked in the summary itself ("[ignores floor: ...]"), not here again."""
    import sys

    from ..analysis.plausibility import ignored_warnings
    from ..support.notices import notice

    inline = set(ignored_warnings(analysis))
    for text in analysis.warnings:
        if text not in inline:
            notice(text, stream=stream or sys.stderr)


def format_matrix(matrix: np.ndarray, indent: str = "  ") -> str:
    """Rows of a matrix, aligned, for the console."""
    return "\n".join(indent + " ".join(f"{v:9.4f}" for v in row) for row in np.atleast_2d(matrix))


def add_analysis_options(parser: argparse.ArgumentParser) -> None:
    """Limits, platform and object options shared by analyze, view and sweep."""
    parser.add_argument(
        "--wheel-velocity-limit", type=decimal, metavar="RAD_S", help="every drive wheel's qdot_max (rad/s)"
    )
    parser.add_argument(
        "--wheel-effort-limit",
        type=decimal,
        metavar="NM",
        help="every drive wheel's tau_max (N m; a skid-steer side pushes with the sum of its wheels')",
    )
    parser.add_argument("--decoupled", action="store_true", help="neglect platform-arm dynamic interaction")
    parser.add_argument("--platform", choices=["own", "fixed"], default="own", help="'fixed' locks the platform")
    add_object_mass_option(parser)
    add_measure_option(parser)


def add_measure_option(parser: Options) -> None:
    """--measure NAME (repeatable): the measures to compute instead of the default ones."""
    from ..measures import default_measures, measure_names

    parser.add_argument(
        "--measure",
        action="append",
        dest="measures",
        metavar="NAME",
        help=f"a measure to compute (repeat for several; default: {', '.join(default_measures())}; "
        f"registered: {', '.join(measure_names())})",
    )
    parser.add_argument(
        "--polytope",
        action="store_true",
        help="also the exact capacity polytopes (" + ", ".join(polytope_measures()) + "): the measures asked "
        "for (default: the default ones) and these, and the polytopes of the other quantities asked for "
        "(--measure force_ellipsoid --polytope adds force_polytope)",
    )


def add_floor_options(parser: Options) -> None:
    """--ground, --mu, --no-traction: the capacity that holds on the floor."""
    parser.add_argument(
        "--ground",
        action="store_true",
        help="capacity that holds on the floor: no support lifts (no tip-over) and the driven wheels stay "
        "within friction (the polytopes honour it; adds dynamic_polytope when no polytope is asked for)",
    )
    parser.add_argument(
        "--mu",
        type=decimal,
        metavar="MU",
        help="friction coefficient of the driven wheels on the floor (implies --ground; default: the spec's "
        "[support] mu, else 0.5)",
    )
    parser.add_argument(
        "--no-traction",
        action="store_true",
        help="on the floor, only no tip-over: the wheels' traction is not limited (implies --ground)",
    )
    parser.add_argument(
        "--load",
        choices=("auto", "compliant", "any"),
        help="how the wheels and casters share the weight (implies --ground): compliant (equally stiff "
        "contacts, every support stays loaded), any (every balancing share: exact tip-over, optimistic "
        "traction); default auto: compliant with a traction limit, any without",
    )
    parser.add_argument(
        "--reserve",
        type=decimal,
        metavar="R",
        help="safety reserve on the floor, a fraction in [0, 1): every support keeps R times its equal "
        "share of the weight, every wheel uses at most 1 - R of its friction (implies --ground; default 0)",
    )
    parser.add_argument(
        "--slope",
        type=decimal,
        metavar="DEG",
        help="the floor is a ramp inclined DEG degrees, 0 to 30 (implies --ground; its axes are the "
        "world's: gravity leans; default 0)",
    )
    parser.add_argument(
        "--uphill",
        type=decimal,
        metavar="DEG",
        help="with --slope: the direction in which the ramp rises, degrees from the world's +x (default 0)",
    )
    parser.add_argument(
        "--level",
        action="store_true",
        help="hold the object level on the floor (implies --ground): the hands also carry its weight and "
        "its roll and pitch moments where the task leaves those rows out, and keep it level within "
        "0.01 m/s^2 and rad/s^2; off by default: the task is the one analysed without the floor",
    )
    add_constraint_options(parser)


def floor_constraints(args) -> tuple:
    """The constraints --ground, --mu, --no-traction, --load and --reserve ask for (empty: the
    ideal robot). A registered constraint option given too is refused, naming the command
    (:func:`constraints_from_args` is for the commands that honour them).

    Raises:
        ArgumentError: contradicting floor options or a bad value.
        UsageError: a registered constraint option the command cannot honour.
    """
    from ..errors import ArgumentError
    from ..robot.support import check_reserve
    from ..terms.constraints.floor import Floor

    refuse_constraint_options(args)

    mu, no_traction = getattr(args, "mu", None), getattr(args, "no_traction", False)
    load, reserve = getattr(args, "load", None), getattr(args, "reserve", None)
    slope, uphill = getattr(args, "slope", None), getattr(args, "uphill", None)
    if uphill is not None and slope is None:
        raise ArgumentError("--uphill says where a ramp rises: give its --slope too")
    level = bool(getattr(args, "level", False))
    if not (
        getattr(args, "ground", False) or mu is not None or no_traction or load or reserve is not None or slope or level
    ):
        return ()
    if mu is not None and no_traction:
        raise ArgumentError("--mu and --no-traction contradict each other: choose one")
    if reserve is not None:
        check_reserve(reserve, "--reserve")
    mu_used = None if no_traction else ("spec" if mu is None else mu)
    return (
        Floor(
            mu=mu_used,
            load=load or "auto",
            reserve=float(reserve or 0.0),
            slope=float(slope or 0.0),
            uphill=float(uphill or 0.0) if slope else 0.0,
            level=level,
        ),
    )


#: Why a command that takes the floor's options cannot honour another constraint (the default:
#: it models the floor on its own).
CANNOT_HONOUR = {
    "brake": "it stops the robot along a path, on rows only the floor has in motion",
    "referee": "it replays the floor in MuJoCo, which models no other constraint",
    "place": "an ellipsoid objective ignores every constraint beyond the joint boxes; give a measure's reading "
    "(e.g. dynamic_polytope:reach:+x)",
}


def add_constraint_options(parser: Options) -> None:
    """The registered constraint options (:mod:`mobmanip.terms.constraints.options`)."""
    from ..terms.constraints.options import CONSTRAINT_OPTIONS

    for option in CONSTRAINT_OPTIONS.values():
        parser.add_argument(option.flag, type=decimal, metavar=option.metavar, dest=option.dest,
                            help=f"{option.help} (a constraint of the {option.problem} problem at rest)")  # fmt: skip


def given_constraint_options(args) -> list:
    """(option, value) for each registered constraint option given, in registration order."""
    from ..terms.constraints.options import CONSTRAINT_OPTIONS

    return [
        (option, getattr(args, option.dest))
        for option in CONSTRAINT_OPTIONS.values()
        if getattr(args, option.dest, None) is not None
    ]


def refuse_constraint_options(args, why: str | None = None) -> None:
    """Refuse, in one line, the registered constraint options given to a command that cannot
    honour them: the option, its constraint's name and ``why`` (default :data:`CANNOT_HONOUR`'s
    line for the command).

    Raises:
        UsageError: one was given.
    """
    from ..errors import UsageError

    given = given_constraint_options(args)
    if given:
        option, value = given[0]
        command = getattr(args, "command", None) or "this command"
        reason = why or CANNOT_HONOUR.get(command, "it models the floor on its own and no other constraint")
        raise UsageError(f"{command} cannot honour {option.flag} ({option.build(value).name}): {reason}")


def constraints_from_args(args, problems: tuple[str, ...] = ("velocity", "acceleration")) -> tuple:
    """Every constraint the options ask for: the floor's (:func:`floor_constraints`), then one per
    registered constraint option given, for a command whose sets honour every constraint of
    ``problems``; an option of another problem is refused by name.

    Raises:
        ArgumentError: a bad value (the constraint's own message).
        UsageError: an option of a problem the command does not solve.
    """
    built, rest = registered_constraints(args, problems)
    return (*floor_constraints(rest), *built)


def registered_constraints(args, problems: tuple[str, ...] = ("velocity", "acceleration")):
    """(the constraints of the registered options given, ``args`` without them): for a command
    that honours constraints of ``problems`` beside its floor options (which ``args`` keeps).

    Raises:
        ArgumentError: a bad value (the constraint's own message).
        UsageError: an option of a problem the command does not solve.
    """
    from ..errors import ArgumentError, UsageError

    given = given_constraint_options(args)
    built = []
    for option, value in given:
        if option.problem not in problems:
            command = getattr(args, "command", None) or "this command"
            raise UsageError(f"{command} cannot honour {option.flag}: its rows are of the {option.problem} problem, "
                             f"and {command} solves the {' and '.join(problems)} problem")  # fmt: skip
        constraint = option.build(value)
        if getattr(constraint, "problem", None) != option.problem:
            raise ArgumentError(f"constraint option {option.flag} declares the {option.problem} problem, but builds "
                                f"a constraint of the {getattr(constraint, 'problem', None)} problem")  # fmt: skip
        built.append(constraint)
    return tuple(built), _without_constraint_options(args, given)


def _without_constraint_options(args, given):
    """``args`` with the registered constraint options cleared (they are built already)."""
    if not given:
        return args
    import copy

    cleared = copy.copy(args)
    for option, _ in given:
        setattr(cleared, option.dest, None)
    return cleared


def add_motion_floor_options(parser: argparse.ArgumentParser) -> None:
    """The floor options of a motion (``carry``, ``retime``): :func:`add_floor_options` and
    ``--zmp-margin``."""
    add_floor_options(parser)
    parser.add_argument(
        "--zmp-margin",
        type=decimal,
        metavar="M",
        help="with --ground: how far the zero-moment point stays inside the support polygon (m; implies --ground; "
        "default 0.02)",
    )


def motion_floor(args, command: str):
    """The floor of a motion (:class:`mobmanip.motion.carry_floor.CarryFloor`) that --ground, --mu,
    --no-traction, --reserve, --zmp-margin, --slope and --uphill ask for, or ``None``. The options
    a motion's floor does not model (the object held level, a load shared any way) are refused,
    naming ``command``, never dropped.

    Raises:
        UsageError: a bad --zmp-margin or an option the motion's floor does not model.
    """
    from ..errors import UsageError
    from ..motion.carry_floor import DEFAULT_ZMP_MARGIN, CarryFloor

    margin = args.zmp_margin
    if margin is not None and not (math.isfinite(margin) and margin >= 0.0):
        raise UsageError(f"--zmp-margin must be a distance >= 0 m, got {margin!r}")
    if args.load not in (None, "auto", "compliant"):
        raise UsageError(f"{command}'s floor shares the load as equally stiff contacts (compliant); --load {args.load} "
                         "is for the capacity sets")  # fmt: skip
    chosen = floor_constraints(args)  # the ramp's angles checked once, by the floor at rest
    if chosen and chosen[0].level:
        raise UsageError(
            f"{command} keeps the object as its task holds it: --level (the object held level on the floor) is "
            f"modelled in the capacity sets, not in {command}"
        )
    if not chosen and margin is None:
        return None
    mu = None if args.no_traction else ("spec" if args.mu is None else args.mu)
    slope, uphill = (chosen[0].slope, chosen[0].uphill) if chosen else (0.0, 0.0)
    return CarryFloor(mu=mu, zmp_margin=DEFAULT_ZMP_MARGIN if margin is None else margin,
                      reserve=float(args.reserve or 0.0), slope=slope, uphill=uphill)  # fmt: skip


def polytope_measures(wanted: tuple[str, ...] = ()) -> tuple[str, ...]:
    """What ``--polytope`` adds: the registered polytopes of the default measures' quantities (the
    capacity polytopes of motion) and of the quantities of the measures ``wanted``."""
    from ..measures import MEASURES, default_measures, get_measure

    quantities = {get_measure(name).quantity for name in (*default_measures(), *wanted)}
    return tuple(
        name for name, measure in MEASURES.items() if measure.set_kind == "polytope" and measure.quantity in quantities
    )


def requested_measures(args) -> tuple[str, ...] | None:
    """The measures ``--measure`` and ``--polytope`` ask for (``None``: the default ones)."""
    from ..measures import default_measures

    measures = getattr(args, "measures", None)
    if getattr(args, "polytope", False):
        wanted = tuple(measures or default_measures())
        measures = wanted + tuple(name for name in polytope_measures(wanted) if name not in wanted)
    asked = tuple(measures or default_measures())
    if constraints_from_args(args) and not set(asked) & set(polytope_measures(asked)):
        measures = asked + ("dynamic_polytope",)
    return measures


def apply_analysis_options(robot, args):
    """The robot with the command line's wheel limits and platform choice applied."""
    if args.wheel_velocity_limit is not None or args.wheel_effort_limit is not None:
        robot = robot.with_wheel_limits(velocity=args.wheel_velocity_limit, effort=args.wheel_effort_limit)
    if args.platform == "fixed":
        robot = robot.with_platform("fixed")
    return robot


def add_dask_option(parser) -> None:
    """--dask ADDRESS: run the command's work on a Dask cluster (or ``local:N``)."""
    parser.add_argument(
        "--dask",
        metavar="ADDRESS",
        help="run on Dask's distributed scheduler: a scheduler address (tcp://HOST:PORT; its workers must "
        "import mobmanip) or local:N (a local cluster of N worker processes)",
    )


def robot_for_workers(name: str) -> str:
    """A robot argument workers on other machines or directories can load: a built-in name as it
    is, a spec path made absolute."""
    from pathlib import Path

    path = Path(name)
    return str(path.resolve()) if path.suffix == ".toml" and path.is_file() else name


def cluster_executor(args):
    """A context giving the Dask executor of ``--dask`` (connected before any work), or None.

    Raises:
        ClusterError: an unreachable scheduler or a malformed address (one line, exit 2).
    """
    import contextlib

    if getattr(args, "dask", None) is None:
        return contextlib.nullcontext(None)
    from ..support.cluster import dask_executor

    return dask_executor(args.dask)


def add_step_options(parser: argparse.ArgumentParser) -> None:
    """--step S and --prepare S: a carry's time step and its longest self-motion before the path
    (``carry``, ``team-carry``)."""
    parser.add_argument("--step", type=decimal, default=0.02, metavar="S", help="time step (s, default 0.02)")
    parser.add_argument(
        "--prepare",
        type=decimal,
        default=30.0,
        metavar="S",
        help="longest self-motion before the path (s, default 30; 0: none)",
    )


def add_page_options(parser: argparse.ArgumentParser, plays: str) -> None:
    """--export PAGE.html and --every K: a self-contained page that plays a motion (``plays``: what
    it shows), drawn every K-th sample."""
    parser.add_argument("--export", metavar="PAGE.html", help=f"write a self-contained page that plays {plays}")
    parser.add_argument(
        "--every", type=int, metavar="K", help="with --export: draw every K-th sample (default: about 200 frames)"
    )


def add_work_option(parser: argparse.ArgumentParser, what: str) -> None:
    """--max-work N: raise the bound on the command's work (see :mod:`mobmanip.support.work`)."""
    parser.add_argument(
        "--max-work",
        type=int,
        metavar="N",
        help=f"the most {what} run without refusing (the estimate is checked before any work)",
    )


def add_progress_option(parser: Options, what: str = "") -> None:
    """``--no-progress``: a long run shows a progress bar on standard error when that is a terminal."""
    suffix = f" for {what}" if what else ""
    parser.add_argument(
        "--no-progress",
        action="store_true",
        help=f"no progress bar{suffix} (one is shown only when standard error is a terminal)",
    )


def show_progress(args) -> bool:
    """Whether to show progress bars: not turned off, and standard error is a terminal (never
    in piped or redirected output)."""
    from ..support.progress import on_terminal

    return not getattr(args, "no_progress", False) and on_terminal()


_BINDING_KINDS = (
    ("level band", "held level"),
    ("tips over about", "tip-over"),
    ("lifts off", "support lifting off"),
    ("slips", "wheel traction"),
    ("limit", "joint effort"),
)


def binding_summary(binding: list[str]) -> str:
    """What stops a maximum, grouped: joint efforts, wheel traction, supports lifting off (a
    team's labels, ``"ROBOT: what"``, name the robot: ``ROBOT/joint``)."""
    groups: dict[str, list[str]] = {}
    for label in binding:
        kind = next((what for key, what in _BINDING_KINDS if key in label), "other")
        robot, sep, rest = label.partition(": ")
        if not sep or " " in robot:
            robot, rest = "", label
        name = rest.split(" ", 1)[0] if kind != "tip-over" else rest.split("tips over ", 1)[-1]
        groups.setdefault(kind, []).append(f"{robot}/{name}" if robot else name)
    return "; ".join(f"{kind}: {', '.join(sorted(set(names)))}" for kind, names in groups.items())


#: How each kind of limit is named in "what stops it" (:data:`mobmanip.terms.constraints.base.ROW_KINDS`).
_KIND_NAMES = {
    "effort": "joint effort",
    "velocity": "joint speed",
    "traction": "wheel traction",
    "contact": "support lifting off",
    "tip-over": "tip-over",
    "level": "held level",
    "user": "constraint",
}
#: At most this many limits are printed in a ranked "what stops it" (the JSON holds them all).
RANKED_SHOWN = 6


def limits_summary(limits: list[dict]) -> str:
    """What stops a maximum, ranked: the limits (:func:`mobmanip.analysis.reaches.limit_entry`
    each, the one worth most first) grouped by kind, the groups in the order of their best limit,
    each limit with what 1 % more of it gives (in the reading's unit): the first is what to change.
    At most :data:`RANKED_SHOWN` are printed, with how many more bind."""
    groups: dict[str, list[str]] = {}
    for entry in limits[:RANKED_SHOWN]:
        label, kind = entry["label"], entry["kind"]
        robot, sep, rest = label.partition(": ")
        if not sep or " " in robot:
            robot, rest = "", label
        if rest.startswith("the robot tips over "):
            name = rest.removeprefix("the robot tips over ")
        elif kind == "user":
            name = rest
        else:
            name = rest.split(" ", 1)[0]
        name = f"{robot}/{name}" if robot else name
        groups.setdefault(_KIND_NAMES.get(kind, kind), []).append(f"{name} +{entry['gain']:.3g}")
    text = "; ".join(f"{kind}: {', '.join(names)}" for kind, names in groups.items())
    if len(limits) > RANKED_SHOWN:
        text += f"; and {len(limits) - RANKED_SHOWN} more, each under +{limits[RANKED_SHOWN - 1]['gain']:.3g}"
    return text


def describe_reaches(reaches: list[dict], unit: str, floor: dict | None) -> str:
    """Per task axis: straight-line reach and support, with what binds and where the ZMP is."""
    head = "  along the task axes, straight-line reach (from rest, exactly along it) and support (others free)"
    lines = [f"{head} ({unit}):"]
    for r in reaches:
        text = f"    {r['axis']:>4}: straight line {r['straight_line']:.4g}, support {r['support']:.4g}"
        if r.get("ideal_straight_line"):  # beside the ideal set's, with what the constraints take
            ideal = r["ideal_straight_line"]
            text += f" (ideal straight line {ideal:.4g}: {100.0 * (r['straight_line'] - ideal) / ideal:+.1f} %)"
        if r.get("limits"):  # ranked by the program's multipliers: the first is what to change
            text += f"; stops it (gain per 1 % more): {limits_summary(r['limits'])}"
        elif r.get("binding"):
            text += f"; stops it: {binding_summary(r['binding'])}"
        ground = r.get("floor")
        if ground and ground.get("zmp") is not None:
            zmp = ", ".join(f"{v:.3f}" for v in ground["zmp"])
            text += f"; ZMP ({zmp}) m, margin {round(ground['margin'], 3) + 0.0:.3f} m"
            if ground.get("next_tip_over_edge"):  # tip-over is the next limit, millimetres away
                a, b = ground["next_tip_over_edge"]
                text += f" (tip-over next: {1e3 * ground['margin']:.1f} mm from tipping about the edge {a} to {b})"
        for robot, ground in (r.get("floors") or {}).items():  # a team: each robot's own floor
            if ground.get("zmp") is not None:
                zmp = ", ".join(f"{v:.3f}" for v in ground["zmp"])
                text += f"; {robot} ZMP ({zmp}) m, margin {round(ground['margin'], 3) + 0.0:.3f} m"
        held = r.get("held")
        if held is not None:
            ms = 1e3 * held["duration"]
            text += f"\n          held {ms:g} ms: straight line {held['straight_line']:.4g}"
            if held["instant_gives_way"] is not None:
                text += (
                    f" (at {100 * held['instant_fraction']:g} % of the maximum the efforts that hold longest give way "
                    f"after {1e3 * held['instant_holds_for']:.3g} ms: {held['instant_gives_way']})"
                )
        lines.append(text)
    if floor is not None:
        mu = "no traction limit" if floor.get("mu") is None else f"mu = {floor['mu']:g}"
        names = ", ".join(c["name"] for c in floor["contacts"])
        ramp = (
            f", a ramp of {floor['slope']:g} deg rising towards {floor['uphill']:g} deg" if floor.get("slope") else ""
        )
        level = ", object held level" if floor.get("level") else ""
        lines.insert(0, f"  on the floor ({mu}, {floor['faces']}-face pyramid{ramp}{level}): contacts {names}")
    return "\n".join(lines)


def add_recording_options(parser: argparse.ArgumentParser) -> None:
    """``--bag RUN`` and its topics and cut: a ROS recording in place of a trajectory file (the
    command's ``trajectory`` positional is then left out)."""
    recording = parser.add_argument_group("a ROS recording instead of TRAJ.csv")
    recording.add_argument("--bag", metavar="RUN", help="a ROS 1 .bag, a ROS 2 .mcap / .db3 file or bag folder")
    recording.add_argument(
        "--joint-states",
        default="auto",
        metavar="TOPIC",
        help="sensor_msgs/JointState topic (default: /joint_states, else the recording's one topic of that type)",
    )
    recording.add_argument(
        "--odom",
        default="auto",
        metavar="TOPIC",
        help="nav_msgs/Odometry topic (default: /odom, else the recording's one topic of that type); 'none' keeps "
        "the platform at the origin",
    )
    recording.add_argument("--start", type=decimal, metavar="S", help="read from S seconds after the recording's start")
    recording.add_argument("--end", type=decimal, metavar="S", help="read up to S seconds after the recording's start")


def check_trajectory_source(args) -> None:
    """One of TRAJ.csv and ``--bag``, and ``--start``/``--end`` only with ``--bag``; a TRAJ.csv
    that is a recording by its first bytes becomes ``--bag``.

    Raises:
        UsageError: both or neither, or a cut without a recording.
    """
    from ..errors import UsageError

    if (args.trajectory is None) == (args.bag is None):
        raise UsageError("give a trajectory: either TRAJ.csv or --bag RUN, not both")
    if args.trajectory is not None:
        from ..motion.recordings import recording_kind

        kind = recording_kind(args.trajectory)
        if kind is not None:  # a recording given where a trajectory file goes: read it as one
            print(f"{args.trajectory} is {kind}: read as --bag {args.trajectory}")
            args.bag, args.trajectory = args.trajectory, None
    if args.bag is None and (args.start is not None or args.end is not None):
        raise UsageError("--start and --end cut a --bag recording")


def read_recorded(robot, args, work):
    """The trajectory of ``--bag`` (its joint-state messages counted against ``work`` before any
    is decoded), its report printed and its gaps and clock jumps warned about."""
    from ..motion.recordings import read_recording
    from ..support.notices import notice

    odometry = None if args.odom.lower() == "none" else args.odom
    recording = read_recording(robot, args.bag, args.joint_states, odometry, start=args.start, end=args.end,
                               work=work)  # fmt: skip
    for line in recording.report.lines():
        print(line)
    for text in recording.report.warnings:
        notice(text)
    return recording.trajectory


def print_self_motion(result, posture: str) -> None:
    """A carry's self-motion before the path, when it made one: how long, how closely the object
    was held and the objective before and after; ``posture``: where the baseline starts."""
    prep = result.preparation
    if prep is not None:
        print(
            f"self-motion before the path ({prep.t[-1] - prep.t[0]:.2f} s, object held within "
            f"{1e3 * prep.tracking_error.max():.3f} mm): {result.objective.name} {prep.capacity[0]:.4g} -> "
            f"{prep.capacity[-1]:.4g}; the QP motion starts there, the baseline from {posture}"
        )


def report_partial_carry(failure, out: str | None, write_partial) -> int:
    """After a carry that failed part-way: without --out (``out`` None) the failure goes on up;
    with it, write what succeeded (``write_partial(failure, out)`` returns the paths), name the
    files kept (flagged partial) and the error in one line; the exit status 2. Returning instead
    of raising lets the command's outputs be published."""
    import sys

    if not out:
        raise failure
    for path in write_partial(failure, out):
        print(f"wrote {path} (partial: up to t = {failure.partial.t[-1]:g} s)")
    print(f"mobmanip: error: {failure}", file=sys.stderr)
    return 2


def print_shared_start(result, mean_ratio: float | None) -> None:
    """Say when the QP motion and the baseline of a carry or a team's carry, set out from one
    posture without a self-motion, are both least at their first step (and clearly: by more than
    1e-6 of its value, so a capacity that stays put is no such case): the ratio of their minima
    is then 1 whatever the motion does, and the ratio of their means is the motion's gain."""
    runs = (result.motion, result.baseline)
    shared = result.preparation is None and all(
        run.capacity.size > 1 and run.capacity[1:].min() - run.capacity[0] > 1e-6 * abs(run.capacity[0]) for run in runs
    )
    if shared and mean_ratio is not None:
        print(
            f"  both runs are least at the start posture they share, so the ratio says nothing of the motion: "
            f"the means' ratio is {mean_ratio:.3f} (--prepare S lets a self-motion raise the start)"
        )
