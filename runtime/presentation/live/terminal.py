"""`rei watch` in a terminal: the running mission as the thesis's monitor showed it.

``TerminalView`` draws a full-screen page (the terminal's alternate screen, as `top` or
`less` use it) with rich (a well-kept, typed terminal library: tables, colours, and
redrawing only what changed, which a hand-written ANSI renderer would have to re-invent):
the mission, simulated time and the simulated-time factor, the robot's geometric state
(thesis Figure 30's FAR, Figure 31's danger zone), every watched object's FAR / CLOSE /
COLLISION state with its distance, the tasks, the latest signals with their utilities and
the total utility. ``LineView`` is the same stream for a pipe or a log: one line per signal
and a closing line. ``Keys`` reads single key presses (q quits) without echo.

Names shown come from the run or a recording: they are drawn as text, never as markup. This
module must never import the simulator.
"""

from __future__ import annotations

import os
import select
import sys
import termios
import time as wallclock
import tty
from collections.abc import Callable, Sequence
from typing import IO, Any

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.presentation.live.frames import (
    GeometricState,
    ObjectState,
    WatchFrame,
    worst_state,
)
from rei.runtime.results import judge

FRAMES_PER_SECOND = 10.0
"""Redraws per wall-clock second at most: a fast replay is not slowed down by drawing."""

_STYLE: dict[str | None, str] = {"FAR": "green", "CLOSE": "bold yellow",
                                 "COLLISION": "bold white on red", None: "dim"}
_VERDICT_STYLE = {"pass": "bold green", "fail": "bold red", "inconclusive": "bold yellow",
                  "error": "bold red", "interrupted": "bold yellow", "unjudged": "dim"}


def _state(state: GeometricState | None) -> str:
    return state if state is not None else "-"


HEAD_LINES = 12
"""Screen lines the page uses besides the objects' rows (titles, status, table heads)."""


MAP_CELLS = (36, 12)
"""At most this many map cells across and down (two characters each across): a larger room
is drawn with several tiles to a cell."""
_MAP_MARKS: dict[str, tuple[int, str, str]] = {
    # role -> (precedence, characters, style): a cell shows its most telling occupant
    "floor": (0, "\u00b7 ", "dim"),
    "wall": (1, "\u2588\u2588", "grey50"),
    "goal": (2, "G ", "bold cyan"),
    "static": (3, "o ", "yellow"),
    "dynamic": (3, "d ", "yellow"),
    "human": (4, "H ", "bold magenta"),
    "robot": (5, "R ", "bold"),
}


def draw_map(frame: WatchFrame, cells: tuple[int, int] = MAP_CELLS) -> Any:
    """The room from above (north up): floors, walls, goals, objects, humans and the robot,
    each in the tile it stands on; the robot and the humans in their state's colour."""
    from rich.text import Text  # noqa: PLC0415

    tile = frame.tile
    places: list[tuple[str, float, float, str | None]] = [
        ("floor", x, y, None) for x, y in frame.floors]
    places += [("goal", x, y, None) for _, x, y in frame.goals]
    places += [(o.role, o.x, o.y, o.state) for o in frame.objects]
    places.append(("robot", frame.robot_pose[0], frame.robot_pose[1], frame.robot_state))
    if not frame.floors or tile <= 0:
        return Text("")
    xs = [p[1] for p in places]
    ys = [p[2] for p in places]
    x0, y1 = min(xs), max(ys)
    columns = round((max(xs) - x0) / tile) + 1
    rows = round((y1 - min(ys)) / tile) + 1
    scale = max(1, -(-columns // cells[0]), -(-rows // cells[1]))
    grid: dict[tuple[int, int], tuple[int, str, str]] = {}
    for role, x, y, state in places:
        cell = (round((x - x0) / tile) // scale, round((y1 - y) / tile) // scale)
        rank, mark, style = _MAP_MARKS.get(role, _MAP_MARKS["static"])
        if role in ("robot", "human") and state in ("CLOSE", "COLLISION"):
            style = _STYLE[state]
        if cell not in grid or grid[cell][0] <= rank:
            grid[cell] = (rank, mark, style)
    text = Text(no_wrap=True, overflow="crop")
    for r in range(-(-rows // scale)):
        for c in range(-(-columns // scale)):
            _, mark, style = grid.get((c, r), (0, "  ", ""))
            text.append(mark, style=style)
        text.append("\n")
    text.rstrip()
    return text


def render(frame: WatchFrame, footer: str = "", max_objects: int | None = None,
           map_cells: tuple[int, int] = MAP_CELLS) -> Any:
    """The page of one frame as a rich renderable (exposed so it can be drawn anywhere).
    With ``max_objects``, the objects beyond it (the farthest walls: the list puts the
    other objects first, then the walls nearest first) are summed up in one row; the map
    takes at most ``map_cells``."""
    from rich.console import Group  # noqa: PLC0415  (rich is imported only to draw)
    from rich.table import Table  # noqa: PLC0415
    from rich.text import Text  # noqa: PLC0415

    factor = f"{frame.time_factor:.1f}x" if frame.time_factor is not None else "-"
    if frame.speed is not None:
        factor += f" (replay at {frame.speed:g}x)"
    title = Text()
    title.append("REI watch  ", style="bold")
    title.append(f"{frame.mission}", style="bold cyan")
    title.append(f" in {frame.world}  seed {frame.seed}")
    status = Text()
    status.append(f"t = {frame.time:8.2f} s   time factor {factor}   ")
    status.append(f"total utility {frame.total_utility:g}", style="bold")
    status.append(f"   signals {frame.signals}")
    robot = Text()
    x, y, yaw = frame.robot_pose
    robot.append("robot ")
    robot.append(_state(frame.robot_state), style=_STYLE[frame.robot_state])
    robot.append(f"  at ({x:.2f}, {y:.2f})  nav {frame.nav_state}  laser ")
    robot.append(_state(frame.laser_state), style=_STYLE[frame.laser_state])
    robot.append("   task ")
    robot.append(frame.task if frame.task is not None else "-", style="bold")

    objects = Table(title="watched objects", title_justify="left", expand=True,
                    show_edge=False, pad_edge=False)
    objects.add_column("object", no_wrap=True, overflow="ellipsis")
    objects.add_column("role")
    objects.add_column("state")
    objects.add_column("distance", justify="right")
    shown = list(frame.objects)
    hidden: list[ObjectState] = []
    if max_objects is not None and len(shown) > max_objects:
        keep = max(max_objects - 1, 0)
        shown, hidden = shown[:keep], shown[keep:]
    for o in shown:
        objects.add_row(Text(o.name), o.role, Text(_state(o.state), style=_STYLE[o.state]),
                        f"{o.distance:.2f} m" if o.distance < 1e3 else "-")
    if hidden:
        worst = worst_state([o.state for o in hidden])
        objects.add_row(Text(f"+ {len(hidden)} more", style="dim"),
                        ", ".join(sorted({o.role for o in hidden})),
                        Text(_state(worst), style=_STYLE[worst]),
                        f">= {min(o.distance for o in hidden):.2f} m")

    tasks = Table(title="tasks", title_justify="left", expand=True, show_edge=False,
                  pad_edge=False)
    tasks.add_column("task", no_wrap=True, overflow="ellipsis")
    tasks.add_column("status")
    for t in frame.tasks:
        style = {"succeeded": "green", "failed": "red"}.get(t.status, "bold")
        tasks.add_row(Text(t.name), Text(t.status + (f": {t.reason}" if t.reason else ""),
                                         style=style))
    signals = Table(title="recent signals", title_justify="left", expand=True,
                    show_edge=False, pad_edge=False)
    # on a narrow screen the names give way, never the numbers
    signals.add_column("time", justify="right", min_width=5, no_wrap=True)
    signals.add_column("signal", no_wrap=True, overflow="ellipsis", ratio=3)
    signals.add_column("utility", justify="right", min_width=4, no_wrap=True)
    signals.add_column("total", justify="right", min_width=5, no_wrap=True)
    signals.add_column("objects", overflow="ellipsis", no_wrap=True, ratio=1)
    for row in frame.recent:
        style = "red" if row.utility < 0 else "green" if row.utility > 0 else ""
        signals.add_row(f"{row.time:.1f}", Text(row.signal, style=style), f"{row.utility:+g}",
                        f"{row.total_utility:g}", Text(";".join(row.objects)))

    body = Table.grid(expand=True, padding=(0, 2))
    body.add_column(ratio=1)
    body.add_column(ratio=1)
    room = Group(Text("map (R robot, H human, o object, G goal)", style="italic"),
                 draw_map(frame, map_cells))
    body.add_row(objects, Group(room, Text(""), tasks, Text(""), signals))
    end = Text()
    if frame.ended is not None:
        verdict = judge(frame.ended)
        end.append(f"mission {frame.ended.outcome} ({frame.ended.reason})   verdict ")
        end.append(verdict.upper(), style=_VERDICT_STYLE.get(verdict, "bold"))
        end.append(f"   total utility {frame.ended.total_utility:g}")
    # the end and the keys stay on top: a long object list never pushes them off the screen
    return Group(title, status, robot, end, Text(footer, style="dim"), body)



class TerminalView:
    """Draws frames full-screen on a terminal (see the module's docstring)."""

    def __init__(self, stream: IO[str] | None = None, footer: str = "q: quit",
                 clock: Callable[[], float] = wallclock.monotonic) -> None:
        self.stream = stream if stream is not None else sys.stdout
        self.footer = footer
        self.clock = clock
        self._live: Any = None
        self._drawn = -1.0

    def start(self, header: StreamHeader) -> None:
        from rich.console import Console  # noqa: PLC0415
        from rich.live import Live  # noqa: PLC0415
        from rich.text import Text  # noqa: PLC0415

        console = Console(file=self.stream, highlight=False)
        self._live = Live(Text(f"REI watch: {header.mission} - waiting for the first sample"),
                          console=console, screen=True, auto_refresh=False,
                          redirect_stdout=False, redirect_stderr=False)
        self._live.start()

    def show(self, frame: WatchFrame, sample: Sample | None, fired: Sequence[SignalRow]
             ) -> None:
        now = self.clock()
        if self._live is None or (sample is not None
                                  and now - self._drawn < 1.0 / FRAMES_PER_SECOND):
            return
        self._drawn = now
        footer = self.footer if frame.ended is None else "the stream ended; q: quit"
        width, height = self._live.console.size
        # the map takes what the screen spares beside the tasks and the latest signals
        spare = height - 6 - (len(frame.tasks) + 3) - (len(frame.recent) + 4) - 2
        cells = (max(min(MAP_CELLS[0], width // 4 - 2), 4), max(min(MAP_CELLS[1], spare), 2))
        self._live.update(render(frame, footer, max(height - HEAD_LINES, 1), cells),
                          refresh=True)

    def close(self) -> None:
        """Leaves the screen as it is: ``leave`` restores the terminal."""

    def leave(self) -> None:
        if self._live is not None:
            self._live.stop()
            self._live = None


class LineView:
    """One line per signal and a closing line: ``rei watch`` into a pipe or a file."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        self.stream = stream if stream is not None else sys.stdout

    def start(self, header: StreamHeader) -> None:
        self._say(f"watching {header.mission} in {header.world} (seed {header.seed})")

    def show(self, frame: WatchFrame, sample: Sample | None, fired: Sequence[SignalRow]
             ) -> None:
        for row in fired:
            objects = f"  {';'.join(row.objects)}" if row.objects else ""
            self._say(f"{row.time:9.2f} s  {row.signal:<36} {row.utility:+5g}  "
                      f"total {row.total_utility:g}{objects}")
        if frame.ended is not None:
            self._say(f"ended at {frame.time:.2f} s: {frame.ended.outcome} "
                      f"({frame.ended.reason}); total utility {frame.total_utility:g}")

    def close(self) -> None:
        self.stream.flush()

    def _say(self, line: str) -> None:
        from rei.lang.errors import printable_lines  # noqa: PLC0415

        print(printable_lines(line), file=self.stream, flush=True)


class Keys:
    """Single key presses from a terminal, unechoed; nothing when stdin is no terminal."""

    def __init__(self, stream: IO[str] | None = None) -> None:
        self.stream = stream if stream is not None else sys.stdin
        self._saved: list[Any] | None = None
        self._fd = -1

    def __enter__(self) -> Keys:
        try:
            fd = self.stream.fileno()
        except (OSError, ValueError):
            return self
        if os.isatty(fd):
            self._fd = fd
            self._saved = termios.tcgetattr(fd)
            tty.setcbreak(fd)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._saved is not None:
            termios.tcsetattr(self._fd, termios.TCSADRAIN, self._saved)
            self._saved = None

    def pressed(self, timeout: float = 0.0) -> str:
        """The keys pressed since the last call ('' when none), waiting up to ``timeout``."""
        if self._saved is None:
            if timeout > 0:
                wallclock.sleep(timeout)
            return ""
        ready, _, _ = select.select([self._fd], [], [], timeout)
        return os.read(self._fd, 64).decode("utf-8", "replace") if ready else ""
