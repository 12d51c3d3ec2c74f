"""`rei replay TRACE --vepl FILE -o DIR`: monitor a recorded trace offline.

TRACE is a trace.jsonl or an MCAP recording (`rei run --record`'s recording.mcap, read
through its /rei/trace channel with the trace's own rules; a recording cut short by a crash
is replayed up to its last complete chunk, as an interrupted run). The trace's samples go
through the same generated automata and evaluator as a live run, so
the event log and verdicts equal the live run's (same trace, same specification). Writes
DIR/events.csv, DIR/summary.json, DIR/automata/automata.py and DIR/report.html (the run's
page, drawn from the trace; its map needs the run's world/ folder beside the trace). Prints
the results on stdout as `rei run` does (``print_results``: the same lines, --quiet and
--verbose), diagnostics on stderr. Exit status: 0 every requirement passed, 1 one failed or
was inconclusive, 2 invalid input (a bad .vepl, an unreadable trace, or a .vepl whose queries
read data the trace does not carry: VEPL-DATA), 3 a monitor error or a recorded run error, 130
a recorded interrupted run.

`rei replay BAG --mission M.mission [--map MAP]` judges a ROS 2 recording REI did not make
(a Gazebo run of the launch target's world, a real robot): an MCAP file or a rosbag2 folder,
read through ``rei.runtime.observation.recordings.foreign`` against the mission's room and goals;
DIR also
gets the stream as REI's trace.jsonl (when its numbers are finite) and the generated world/.
Data no verdict may rest on (gaps, stamps going backwards, non-finite values, bad scans)
turns every verdict that would pass into inconclusive, naming the problem.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rei.lang.cli_support import EXIT_BAD_INPUT, EXIT_RUN_ERROR
from rei.lang.errors import printable_lines
from rei.lang.vepl_parameters import (
    ParameterValues,
    add_functions_option,
    add_parameter_option,
    parameter_values,
)
from rei.runtime.commands.run import (
    REPLAY_VERBOSE_HELP,
    add_verbosity,
    print_results,
    write_page,
)
from rei.runtime.observation.judgement import judge_stream
from rei.runtime.results import RunSummary

# The messages only as type names: importing them (numpy) with every `rei` command line
# would cost each command's process ~0.15 CPU s, and leave numpy's threads in `rei run`'s
# supervising process, which then cannot fork its simulation (rei.runtime.platform.warm).
if TYPE_CHECKING:
    pass

HELP_EXAMPLES = """\
rei replay out/nav/trace.jsonl -o out/nav-strict --vepl examples/navigation/human_safety.vepl
rei replay out/rec/recording.mcap -o out/rec-again -v     # every requirement, with reasons
rei replay out/nav/trace.jsonl -o out/nav07 --param react_zone=0.7  # judged as your robot's
rei replay my_bag/ --mission examples/simple_wall/simple_wall.mission -o out/bag
rei replay run.mcap --mission m.mission --map rei_bag_map.toml -o out/bag
"""


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = sub.add_parser(
        "replay", help="monitor a recorded trace (or recording.mcap) with the event automata "
                       "of a .vepl file",
        description="Feed a trace recorded by `rei run` (trace.jsonl, or the recording.mcap "
                    "of `rei run --record`) through the event automata generated from a .vepl "
                    "specification (the default one unless --vepl) and write events.csv, "
                    "summary.json and report.html (the run's page). Same trace and "
                    "specification give the same events and verdicts as the live run. A "
                    "recording cut short by a crash is replayed up to its last complete chunk "
                    "and judged as an interrupted run. With --mission, TRACE is a ROS 2 "
                    "recording REI did not make (MCAP file or rosbag2 folder), judged against "
                    "the mission's room and goals. Results go to stdout, diagnostics to "
                    "stderr. Exit status: 0 every requirement passed, 1 one failed or was "
                    "inconclusive (or the .vepl declares no requirement: verdict UNJUDGED, "
                    "never a pass), 2 invalid input (a bad .vepl, an unreadable trace, a .vepl "
                    "reading data the trace lacks), 3 a monitor error or a recorded run error, "
                    "130 a recorded interrupted run.")
    parser.add_argument("trace", type=Path, metavar="TRACE",
                        help="a trace.jsonl file or an MCAP recording (.mcap); with --mission "
                             "a ROS 2 recording: an MCAP file or a rosbag2 folder")
    parser.add_argument("--mission", type=Path, default=None, metavar="M.mission",
                        help="judge TRACE as a ROS 2 recording of this mission (from Gazebo "
                             "or a real robot): ground truth from /tf (frames named as the "
                             "room's bodies), belief from /odom, /scan, /cmd_vel, mission "
                             "progress from Nav2's navigate_to_pose status or the poses; "
                             "REI's own recording.mcap is then judged from its ROS channels "
                             "alone")
    parser.add_argument("--map", type=Path, default=None, metavar="MAP.toml",
                        dest="topic_map",
                        help="with --mission: rename topics and frames for another stack, a "
                             "TOML file with [topics] (\"/scan\" = \"/robot1/scan\") and "
                             "[frames] (map = \"world\"); see docs/recording.md")
    parser.add_argument("--vepl", type=Path, default=None, metavar="FILE",
                        help="the specification (default: REI's default.vepl); its queries "
                             "may read only the data the trace carries (its header's "
                             "\"data\"), else exit 2")
    add_parameter_option(parser)
    add_functions_option(parser)
    parser.add_argument("-o", "--output", type=Path, required=True, metavar="DIR",
                        help="output folder (created if missing)")
    add_verbosity(parser, REPLAY_VERBOSE_HELP)
    parser.set_defaults(func=run)


def replay(trace: Path, vepl: Path | None, out_dir: Path,
           functions: str | None = None, parameters: ParameterValues = ()) -> RunSummary:
    """Monitor ``trace`` into ``out_dir`` (with ``parameters`` from `--param` in place of the
    specification's values); the summary (also written as summary.json)."""
    from rei.runtime.observation.monitor import generate_automata  # noqa: PLC0415
    from rei.runtime.observation.monitor.functions import load_functions  # noqa: PLC0415
    from rei.runtime.observation.recordings import read_stream  # noqa: PLC0415

    # The specification is checked and generated before the trace is opened: a bad .vepl
    # is reported without touching the trace.
    automata = generate_automata(vepl, Path(out_dir) / "automata", replace=True,
                                 parameters=parameters)
    user = load_functions(functions, vepl)
    header, samples, read_end = read_stream(trace)
    return judge_stream(header, samples, read_end, vepl, out_dir, user, automata,
                        f"the trace '{trace}'", parameters=parameters)


def replay_bag(bag: Path, mission_path: Path, vepl: Path | None, out_dir: Path,
               functions: str | None = None, topic_map: Path | None = None,
               parameters: ParameterValues = ()) -> RunSummary:
    """Judge the ROS 2 recording ``bag`` (MCAP file or rosbag2 folder) as a run of
    ``mission_path`` into ``out_dir``; the summary (also written as summary.json)."""
    from rei.lang.vepl.document import load_vepl  # noqa: PLC0415
    from rei.runtime.artifacts.monitor_config import load_monitor_config  # noqa: PLC0415
    from rei.runtime.artifacts.world import load_manifest  # noqa: PLC0415
    from rei.runtime.observation.monitor import generate_automata  # noqa: PLC0415
    from rei.runtime.observation.monitor.functions import load_functions  # noqa: PLC0415
    from rei.runtime.observation.monitor.needs import check_needs  # noqa: PLC0415
    from rei.runtime.observation.recordings.foreign import (  # noqa: PLC0415
        BagSamples,
        BagWorld,
        load_topic_map,
    )
    from rei.runtime.simulation.assembly import generate_world, stream_header  # noqa: PLC0415
    from rei.runtime.trace import TraceWriter  # noqa: PLC0415

    out_dir = Path(out_dir)
    automata = generate_automata(vepl, out_dir / "automata", replace=True,
                                 parameters=parameters)
    user = load_functions(functions, vepl)
    mapping = load_topic_map(topic_map) if topic_map is not None else None
    world_dir = out_dir / "world"
    mission = generate_world(mission_path, world_dir, replace=True)
    manifest = load_manifest(world_dir)
    header = stream_header(manifest, load_monitor_config(world_dir), mission, 0)
    check_needs(load_vepl(vepl, parameters), header.data,
                f"the mission '{mission.name}' to collect",
                "name that data in the mission's monitor block, or drop the query")
    world = BagWorld(header, mission.tasks(),
                     tuple((b.x, b.y, b.yaw) for b in manifest.observed), mission.settle)
    samples = BagSamples(bag, world, mapping)
    (out_dir / "trace.jsonl").unlink(missing_ok=True)
    return judge_stream(header, samples, samples.end, vepl, out_dir, user, automata,
                        f"the mission '{mission.name}'",
                        trace=TraceWriter(out_dir / "trace.jsonl"), parameters=parameters)


def run(args: argparse.Namespace) -> int:
    from rei.runtime.observation.errors import MonitorError  # noqa: PLC0415

    if args.topic_map is not None and args.mission is None:
        print("rei replay: error: --map: expected --mission too (a mapping renames a ROS 2 "
              "recording's topics and frames), found --map alone", file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.mission is not None:
            summary = replay_bag(args.trace, args.mission, args.vepl, args.output,
                                 args.functions, args.topic_map, parameter_values(args.param))
        else:
            summary = replay(args.trace, args.vepl, args.output, args.functions,
                             parameter_values(args.param))
    except MonitorError as exc:
        print(f"rei replay: error: {printable_lines(str(exc))}", file=sys.stderr)
        return EXIT_RUN_ERROR
    page = write_page(args.output, args.trace if args.mission is None else None)
    # the one pass rule of `rei run`; a recorded run error stays an error
    return print_results(summary, args.output, page=page, quiet=args.quiet,
                         verbose=args.verbose)
