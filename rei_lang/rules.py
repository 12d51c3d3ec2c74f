"""Every rule REI checks in its languages, by id: the one list the docs and tests read.

The checks themselves live with the language stage that can decide them (linker, layout,
catalogue checks); this table documents them and a test keeps it complete both ways.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Rule:
    id: str
    languages: str
    summary: str
    source: str = ""
    """Where the rule comes from: a thesis section, or why a user wants it caught."""


RULES: tuple[Rule, ...] = (
    Rule("INPUT-READ", "all", "the file exists, is a regular file (not a folder, FIFO or "
         "device, which are never opened) and can be read; a symbolic link loop is named"),
    Rule("INPUT-KIND", "all", "the file ends in a known suffix (a mission imports a .room "
         "file, nothing else is read as one)"),
    Rule("INPUT-EMPTY", "all", "the file is not empty"),
    Rule("INPUT-SIZE", "all", "the file is at most 32 MiB (at most that much is ever read)"),
    Rule("INPUT-ENCODING", "all", "the file is UTF-8 text (no NUL bytes)"),
    Rule("INTERNAL", "all", "the editor shows a failure of REI's own checks as a diagnostic "
         "(please report it): a file is never shown clean because a check broke"),
    Rule("SYNTAX", "all", "the text follows the grammar (the parser stops at the first error)"),
    Rule("SYNTAX-DEPTH", "all", "the text does not nest deeper than the parser can follow "
         "(located at the deepest bracket)"),
    Rule("NUM-FINITE", "all", "every number is finite (no inf, nan, or overflow like 1e999)"),
    Rule("NUM-RANGE", "all", "every number lies in its field's range (tile 0.05..100 m, times "
         ">= 0, headings within +-360 degrees, ...)"),
    Rule("OPTION-REPEAT", "all", "a setting or option is given at most once"),
    Rule("NAME-UNIQUE", "room, mission", "every name is unique", "thesis 4.1.2"),
    Rule("NAME-PATH", "room", "names are safe as file names (no device names, at most 100 "
         "characters); the grammar already admits only letters, digits and '_'",
         "names become file names of generated artifacts"),
    Rule("REF-UNRESOLVED", "room, mission", "every referenced name is declared (with 'did you "
         "mean')"),
    Rule("REF-KIND", "room, mission", "a reference names the right kind of element (neighbours "
         "are floors or walls; objects, trajectory vertices and goals are on floors)",
         "thesis 4.1.2"),
    Rule("LINK-SELF", "room", "a floor is not its own neighbour"),
    Rule("LINK-REPEAT", "room", "a floor names at most one neighbour per side"),
    Rule("LINK-ASYMMETRIC", "room", "neighbour links agree: A.right = B means B.left is A "
         "(or unset)"),
    Rule("LINK-GEOMETRY", "room", "links agree with the traversal's placement of floors",
         "thesis 6.2.1"),
    Rule("FLOOR-OVERLAP", "room", "no two building blocks land in one cell"),
    Rule("FLOOR-DISCONNECTED", "room", "every floor is connected to the robot's floor"),
    Rule("WALL-ORPHAN", "room", "every wall is the neighbour of a floor", "thesis 4.1.2"),
    Rule("WALL-PLACEMENT", "room", "a wall named by several floors lands in one cell"),
    Rule("GRID-SYMBOL", "room", "grid cells use legend symbols; a named cell appears once"),
    Rule("GRID-LEGEND", "room", "legend symbols are single characters; empty cells have no "
         "name"),
    Rule("ROBOT-COUNT", "room", "exactly one robot, on a floor", "thesis 4.1.2"),
    Rule("ROBOT-FIT", "room", "the robot can turn in place on one tile"),
    Rule("OBJECT-FIT", "room", "an object's footprint fits its tile (objects stand at a floor's "
         "centre, or moved by an `offset` that keeps the footprint on the tile)", "thesis 4.1.2"),
    Rule("OFFSET-TILE", "room, mission", "an `offset DX DY` of a trajectory vertex or a goal "
         "keeps the point on its floor's tile (at most half a tile either way)"),
    Rule("OBJECT-OVERLAP", "room", "at most one object on a floor at the start"),
    Rule("CATALOGUE-TYPE", "room", "every type is in the catalogue (with 'did you mean')"),
    Rule("CATALOGUE-KIND", "room", "a type's kind matches its use (a table is not a robot)"),
    Rule("CATALOGUE-FILE", "room", "the room's own catalogue file is valid"),
    Rule("CATALOGUE-SYNTAX", "catalogue", "the catalogue is valid TOML"),
    Rule("CATALOGUE-FIELD", "catalogue", "every field of a type is known, of the right type, "
         "finite and in range"),
    Rule("TRAJ-VERTICES", "room", "a trajectory has at least two control vertices"),
    Rule("TRAJ-TIMES", "room", "a trajectory has a time on every vertex (increasing) or a "
         "total time", "thesis 4.2.1"),
    Rule("TRAJ-SPEED", "room", "a trajectory's body moves at most 10 m/s between consecutive "
         "vertices, which are at least 0.01 s apart (times as the generators write them: "
         "a 'total' shared out by length, a loop's way back at its mean speed)",
         "the animator walks every accepted trajectory"),
    Rule("TRAJ-START", "room", "a trajectory starts on its object's floor"),
    Rule("TRAJ-BLOCKED", "room", "no trajectory vertex lies on a floor with a standing object",
         "thesis 4.1.2"),
    Rule("TRAJ-CROSSES", "room", "the curve a moving body walks (the Catmull-Rom spline through "
         "its timed vertices, swept with its footprint's radius) stays on the floors, clear of "
         "walls and standing objects", "thesis 4.2.1"),
    Rule("TRAJ-UNREACHABLE", "room", "trajectory vertices lie where the robot can reach"),
    Rule("HUMAN-BEHAVIOUR", "room", "a human's behaviour is scripted, yielding or social"),
    Rule("MISSION-ROOM", "mission", "the imported room exists and is valid"),
    Rule("MISSION-GOALS", "mission", "a mission has at least two goals (start and final place)",
         "thesis 4.1.2, 4.3.1"),
    Rule("GOAL-UNREACHABLE", "mission", "the robot's footprint can reach every goal from its "
         "start (path search on the floor graph without blocked floors)"),
    Rule("MONITOR-DATA", "mission", "the monitor block names known data (ground_truth, "
         "odometry, laser, nav_state, mission_events), each once, ground_truth among them; its "
         "rate is more than 0 and at most 1000 samples per second", "thesis 3.2.2.2, 6.1.2"),
    Rule("FAULT-KIND", "mission", "every fault in a mission's fault section (or a --fault "
         "option) is a known kind: laser_poisson, laser_noise, laser_dropout, laser_freeze, "
         "laser_delay, laser_sector, odom_drift, odom_jump, cmd_drop, cmd_delay (with 'did you "
         "mean')", "issue 17, thesis 7.5"),
    Rule("FAULT-PARAM", "mission", "a fault's parameters are its kind's own (with 'did you "
         "mean'), the required ones present, and they make sense together (a drift or jump "
         "of something, a sector's min_deg <= max_deg)", "issue 17"),
    Rule("FAULT-ACTIVATION", "mission", "a fault's activation is a time window that ends after "
         "it starts, or starts on a signal and stops after a duration > 0 or on another "
         "signal", "issue 17"),
    Rule("FAULT-SIGNAL", "mission", "`rei run` refuses a fault started or stopped by a signal "
         "the monitoring specification does not define, or by any signal on a run without "
         "the monitor: it would never fire, and the fault would silently never act",
         "issue 17"),
    Rule("FAULT-WINDOW", "mission", "`rei run` refuses a fault whose time window starts at or "
         "after the run's end (the mission's time limit, or --duration), holds no control "
         "tick (no scan for a scan fault), or lasts ('for') no longer than a signal takes to "
         "act: it would silently never act", "issue 17"),
    Rule("FAULT-NAME", "mission", "`rei run` refuses two faults of one run (the mission's and "
         "--fault's) with the same name: the summary and events.csv tell faults by name",
         "issue 17"),
    Rule("VEPL-DATA", "vepl", "`rei run` and `rei replay` refuse a specification whose queries "
         "read data the mission does not collect or the trace does not carry (laser_min without "
         "laser, ...)", "thesis 6.1.2"),
    Rule("VEPL-UNKNOWN", "vepl", "every referenced name is declared (queries, events, signals, "
         "parameters, functions, states) and every kind in object[...] is a role or a "
         "catalogue type, with 'did you mean'"),
    Rule("VEPL-ARITY", "vepl", "a query has at most four parameters; finds, query events and "
         "function calls pass the declared number of arguments"),
    Rule("VEPL-FUNCTION", "vepl", "every declared user function is found in the module "
         "given with --functions"),
    Rule("VEPL-ORDER", "vepl", "an event is defined before a complex event, signal or "
         "requirement uses it"),
    Rule("VEPL-WINDOW", "vepl", "a time window is more than 0 and at most 1e9 ms"),
    Rule("VEPL-TYPE", "vepl", "expressions combine the right kinds of values "
         "(distance(robot, object), state(t) == STATE, conditions under and/or/not)"),
    Rule("VEPL-NOT-WINDOW", "vepl", "a pattern that ends in NOT has a time window"),
    Rule("VEPL-MULTIPLICITY", "vepl", "{n} is a whole number from 1 to 100"),
    Rule("VEPL-CYCLE", "vepl", "queries do not find each other in a circle"),
    Rule("VEPL-LIMIT", "vepl", "a complex event's pattern has at most 500 parts with every "
         "{n} and {+} written out, and operators nested at most 50 deep; a query's condition "
         "has at most 2,000 operators and operands",
         "the generated automata must load and run: nested {+} double a pattern's automaton"),
    Rule("VEPL-PARAM", "vepl", "eps_collision is below eps_close and the hysteresis band is "
         "at least 0"),
)

RULE_IDS = frozenset(r.id for r in RULES)
