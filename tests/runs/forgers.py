"""Controllers that try to forge their own result, for tests/runs/test_forged_results.py.

Each drives into the wall of examples/simple_wall (an honest FAIL) and at its 20th step tries
to make `rei run` report something else. Importable as `tests.runs.forgers:NAME`.
"""

from __future__ import annotations

import atexit
import json
import os
import signal
import sys
from pathlib import Path

from rei.runtime.robot import ControllerContext, VelocityCommand
from tests.robot.faulty import _Base


class ForgesPipeAndExits(_Base):
    """Tells the supervisor over its pipe (the descriptor in the child's argv) that the run
    ended with exit status 0, then ends the process without a summary."""

    def fault(self) -> VelocityCommand:
        for word in sys.argv[1:]:
            if word.isdigit():
                try:
                    os.write(int(word), b'{"exit": 0, "wall": 1.0, "cpu": 1.0}\n')
                except OSError:
                    pass
        os._exit(0)


class RewritesSummaryAtExit(_Base):
    """Registers an exit hook that rewrites summary.json (named by REI_FORGE_OUT) as a pass
    once the run has written it."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        atexit.register(_claim_pass, Path(os.environ["REI_FORGE_OUT"]) / "summary.json")

    def fault(self) -> VelocityCommand:
        return VelocityCommand(0.2, 0.0)


def _claim_pass(path: Path) -> None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return
    data["outcome"], data["reason"], data["verdict"] = "completed", "all good", "pass"
    for verdict in data.get("verdicts", []):
        verdict["status"] = "pass"
    path.write_text(json.dumps(data), encoding="utf-8")


class KillsTheSimulationWhenMade(_Base):
    """Kills the simulation process (its parent: it runs in a process of its own) while REI
    makes it, before the run has written anything of its own."""

    def __init__(self) -> None:
        os.kill(os.getppid(), signal.SIGKILL)
        super().__init__()


class ChangesFolder(_Base):
    """Moves the process to another working folder (REI_FORGE_ELSEWHERE) in reset()."""

    def reset(self, context: ControllerContext) -> None:
        super().reset(context)
        os.chdir(os.environ["REI_FORGE_ELSEWHERE"])

    def fault(self) -> VelocityCommand:
        return VelocityCommand(0.2, 0.0)
