"""The host of the generated event automata: it turns each sample into query events,
pushes them through the RxPY automata on a virtual-time scheduler advanced with the
simulation clock, and hands signals and events to the evaluator.

Per sample: the queries are evaluated once, vectorised; when any match changed, the
crossings of every threshold between the previous and this sample are replayed in order
(a jump FAR -> COLLISION passes through CLOSE); then each mission event of the sample is
applied and the queries evaluated again. Within a step, every 'lost' event comes before
every 'found' event (so `notA -> B` sees a state change in order). Bad samples are
counted and skipped. This module must never read the wall clock or import the simulator.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from reactivex.scheduler import VirtualTimeScheduler
from reactivex.subject import Subject

from rei.lang.vepl.document import DEFAULT_VEPL
from rei.lang.vepl_parameters import ParameterValues
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.automata.patterns import Occurrence
from rei.runtime.observation.automata.records import QueryEventSpec, QueryInputs, load_generated
from rei.runtime.observation.errors import MonitorError
from rei.runtime.observation.evaluator.margins import MarginTracker
from rei.runtime.observation.evaluator.signal_log import SignalLog
from rei.runtime.observation.evaluator.summary import MonitorResult
from rei.runtime.observation.evaluator.verdicts import RequirementChecker
from rei.runtime.observation.model.interpolation import crossings, interpolate
from rei.runtime.observation.model.runtime_model import RuntimeModel
from rei.runtime.observation.model.sample_checks import SampleProblems, check_sample

UserFunction = Callable[..., Any]
FINISHED = ("completed", "failed")
"""Outcomes after which the run's evidence is complete (timeout, error, interrupted: not)."""


def generate_automata(vepl: str | Path | None, out_dir: str | Path,
                      replace: bool = False, parameters: ParameterValues = ()) -> Path:
    """Generate the `rx` target of a .vepl file (the default one when None) into out_dir
    (with ``replace``, whatever else was in it goes), with ``parameters`` (`--param`) in
    place of the file's values."""
    from rei.generators.output import write_tree  # noqa: PLC0415  (generation is a stage above)
    from rei.generators.pipeline import plan  # noqa: PLC0415

    source = Path(vepl) if vepl is not None else DEFAULT_VEPL
    result = plan(source, "rx", parameters=parameters)
    write_tree(result.tree, out_dir, replace=replace)
    return Path(out_dir) / "automata.py"


class AutomataHost:
    """One run of one generated module; not reusable across runs."""

    def __init__(self, module: ModuleType, header: StreamHeader,
                 functions: Mapping[str, UserFunction] | None = None) -> None:
        missing = sorted(set(module.FUNCTIONS) - set(functions or {}))
        if missing:
            raise MonitorError(f"the specification '{module.SPEC_NAME}' expected the user "
                               f"function(s) {', '.join(missing)} to be registered, found none")
        self.module = module
        self.header = header
        self.functions = dict(functions or {})
        self.model = RuntimeModel(header, module.DISTANCE_CUTOFF)
        self.domains: dict[str, tuple[str, ...]] = {q.name: tuple(q.domains)
                                                    for q in module.QUERIES}
        self.lost_first: tuple[QueryEventSpec, ...] = tuple(
            e for e in module.QUERY_EVENTS if not e.found) + tuple(
            e for e in module.QUERY_EVENTS if e.found)
        self.problems = SampleProblems()
        self.scheduler = VirtualTimeScheduler(0.0)
        self.atomic: Subject[Occurrence] = Subject()
        self.events = module.build_automata(self.atomic, self.scheduler)
        self.log = SignalLog({s.name: s.utility for s in module.SIGNALS},
                             with_faults=bool(header.faults))
        self.faults: tuple[str, ...] = ()
        """The injected faults active at the sample being judged (events.csv names them)."""
        self.checker = RequirementChecker(module.REQUIREMENTS, set(self.domains),
                                          self.model.describe)
        self.watched_queries = sorted(self.checker.watched_queries())
        self.margin_tracker = MarginTracker(module.REQUIREMENTS, module.PARAMETERS,
                                     header.mission_facts)
        self._last_holding: tuple[bool, ...] = ()
        for name in sorted(self.checker.watched_events()):
            if name in self.events:
                self.events[name].subscribe(
                    lambda e, n=name: self.checker.on_event(n, e.time, e.objects))
        module.build_signals(self.events).subscribe(self._on_signal)
        signal_names = {s.name for s in module.SIGNALS}
        self._signal_watch = signal_names & self.checker.watched_events()
        baseline = self.model.baseline()
        baseline.functions = self.functions
        self.prev_inputs: QueryInputs = baseline
        self.prev_q: dict[str, Any] = module.evaluate_queries(baseline, {})
        self.serial = 0
        self.last_seq: int | None = None
        self.last_time = -math.inf
        self.first_time: float | None = None
        self.samples = 0
        self.listeners: list[Callable[[str, float], None]] = []
        """Told (name, time) of every signal fired (the run loop's fault stage)."""

    def _on_signal(self, e: Occurrence) -> None:
        self.log.add(e.name, e.time, e.objects, self.faults)
        for listener in self.listeners:
            listener(e.name, e.time)
        if e.name in self._signal_watch:
            self.checker.on_event(e.name, e.time, e.objects)

    # ---- samples ----------------------------------------------------------------------------

    def feed(self, s: Sample) -> None:
        if self.last_seq is not None and s.seq <= self.last_seq:
            self.problems.add("duplicate" if s.seq == self.last_seq else "out_of_order",
                              self.last_time)
            return
        if not s.time > self.last_time:
            self.problems.add("out_of_order", self.last_time)
            return
        self.faults = s.faults
        problem = check_sample(s, self.header)
        if problem is not None:
            self.problems.add(problem, self.last_time if not math.isfinite(s.time) else s.time)
            if math.isfinite(s.time):
                # the geometry is unusable, the mission events are not: keep the
                # mission and task states (and their signals) right
                self.last_seq, self.last_time = s.seq, s.time
                self._mission_events(s, self.prev_inputs)
            return
        # samples are numbered from 0: a first sample numbered n > 0 (a monitor that joined
        # late) follows n missing ones
        previous = -1 if self.last_seq is None else self.last_seq
        if s.seq > previous + 1:
            self.problems.add("missing", s.time, s.seq - previous - 1)
        self.last_seq, self.last_time = s.seq, s.time
        if self.first_time is None:
            self.first_time = s.time
        self.samples += 1
        # NOT windows that closed before this sample fire now. Only timers need the clock
        # (they are scheduled at absolute times), so an empty queue is not advanced: that
        # keeps the common sample free of the scheduler's bookkeeping.
        if self.scheduler._queue:  # noqa: SLF001  (reactivex 6.1 VirtualTimeScheduler)
            self.scheduler.advance_to(s.time)
        w = self.model.observe(s)
        w.functions = self.functions
        self.margin_tracker.observe(w)
        q = self.module.evaluate_queries(w, self.prev_q)
        if self._changed(q):
            before = self.module.margins(self.prev_inputs)
            after = self.module.margins(w)
            fractions = crossings(before, after)
            for lo, hi in zip(fractions, fractions[1:], strict=False):
                step = interpolate(self.prev_inputs, w, (lo + hi) / 2)
                self.margin_tracker.observe(step)  # the queries see the crossings: so do margins
                self._step(self.module.evaluate_queries(step, self.prev_q), s.time)
            q = self.module.evaluate_queries(w, self.prev_q)
            self._step(q, s.time)
        elif self.watched_queries:
            self._holding(q, s.time)
        self.prev_q = q
        self.prev_inputs = self._mission_events(s, w)

    def _mission_events(self, s: Sample, w: QueryInputs) -> QueryInputs:
        for event in s.events:
            w = self.model.apply(event, w)
            self.margin_tracker.observe(w)
            if event.kind in ("task_success", "task_fail"):
                key = str(event.index) if event.index is not None else (event.task or "")
                record = next((t for t in self.model.tasks if t.key == key), None)
                if record is not None and record.ended is not None:
                    self.margin_tracker.task_ended(w, record.index, record.ended - record.started,
                                            event.kind == "task_success", record.cause)
            self._step(self.module.evaluate_queries(w, self.prev_q), s.time)
        return w

    def _changed(self, q: dict[str, Any]) -> bool:
        prev = self.prev_q
        for name, new in q.items():
            old = prev[name]
            if old.shape != new.shape or old.tobytes() != new.tobytes():
                return True
        return False

    def _holding(self, q: dict[str, Any], time: float) -> None:
        holding = tuple(bool(q[n].any()) for n in self.watched_queries)
        if holding != self._last_holding or self.checker.waiting():
            self.checker.on_step(time, dict(zip(self.watched_queries, holding, strict=False)))
            self._last_holding = holding

    def _step(self, q: dict[str, Any], time: float) -> None:
        """Emit the query events between ``self.prev_q`` and ``q``, lost before found."""
        for spec in self.lost_first:
            new = q[spec.query]
            old = self.prev_q[spec.query]
            domains = self.domains[spec.query]
            if np.shape(old) != np.shape(new):  # tasks appeared since: they matched nothing
                grown = np.zeros(np.shape(new), dtype=bool)
                grown[tuple(slice(0, n) for n in np.shape(old))] = old
                old = grown
            if spec.per_match:
                changed = (new & ~old) if spec.found else (old & ~new)
                if changed.any():
                    for match in np.argwhere(changed):
                        self._emit(spec.name, time, self._match_names(domains, match))
            else:
                now_any, was_any = bool(new.any()), bool(old.any())
                if spec.found and now_any and not was_any:
                    self._emit(spec.name, time, self._objects(domains, new))
                elif not spec.found and was_any and not now_any:
                    self._emit(spec.name, time, self._objects(domains, old))
        self.prev_q = q
        if self.watched_queries:
            self._holding(q, time)

    def _match_names(self, domains: tuple[str, ...], match: np.ndarray) -> tuple[str, ...]:
        """The names of one match: an object, floor or task per parameter."""
        return tuple(self.model.names(d)[int(i)] for d, i in zip(domains, match, strict=True))

    def _objects(self, domains: tuple[str, ...], mask: Any) -> tuple[str, ...]:
        """Everything the matches name, each once, in the order of the matches."""
        if not domains:
            return ()
        names: dict[str, None] = {}
        for match in np.argwhere(mask):
            names.update(dict.fromkeys(self._match_names(domains, match)))
        return tuple(names)

    def _emit(self, name: str, time: float, objects: tuple[str, ...]) -> None:
        self.serial += 1
        self.atomic.on_next(Occurrence(name, time, objects, self.serial))

    # ---- end ----------------------------------------------------------------------------------

    def finish(self, end_time: float, outcome: str, reason: str = "") -> MonitorResult:
        end = max(end_time, self.last_time) if math.isfinite(end_time) else self.last_time
        if math.isfinite(end) and self.scheduler._queue:  # noqa: SLF001  (see feed)
            self.scheduler.advance_to(end)  # windows still open at the end close now
        end = end if math.isfinite(end) else 0.0
        finished = outcome in FINISHED
        verdicts = self.margin_tracker.annotate(self.checker.verdicts(
            end, self.problems, finished,
            f"outcome {outcome}" + (f": {reason}" if reason else "")))
        return MonitorResult(self.log.total, self.log.counts(), verdicts,
                             self.measurements(end), end - (self.first_time or 0.0))

    def measurements(self, end: float) -> dict[str, Any]:
        m = self.model
        goals = [{"task": t.name, "index": t.index, "started": t.started, "ended": t.ended,
                  "status": t.status,
                  "time_to_goal": None if t.ended is None else t.ended - t.started}
                 for t in m.tasks]
        return {
            "min_distance_to_human": None if math.isinf(m.min_distance_to_human)
            else m.min_distance_to_human,
            "min_distance_to_human_moving": None if math.isinf(m.min_distance_to_human_moving)
            else m.min_distance_to_human_moving,
            "path_length": m.path_length,
            "pushed": {"seconds": m.pushed_time, "top_speed": m.pushed_top_speed},
            "settle_travel": m.idle_travel,
            "situations": m.situations.to_json(),
            "efficiency": [{"task": name, "shortest": None if math.isinf(e.shortest)
                            else e.shortest, "path_ratio": e.path_ratio,
                            "time_ratio": e.time_ratio, "goal_spin": e.spin}
                           for name, e in m.efficiency],
            "time_to_goal": goals,
            "samples": self.samples,
            "sample_problems": dict(self.problems.counts),
            "specification": self.module.SPEC_NAME,
        }


class MonitorSink:
    """A sample sink that monitors a run with the automata of a .vepl file.

    ``MonitorSink(vepl, out_dir)``: ``vepl`` None means the default specification (with
    ``parameters`` from `--param` in place of its values); the
    automata are generated into ``out_dir/automata/`` and loaded at ``start``, which refuses
    (``LanguageError``, VEPL-DATA) a specification reading data the header does not name;
    ``finish`` writes ``out_dir/events.csv`` and keeps the result (``self.result``).
    """

    def __init__(self, vepl: str | Path | None, out_dir: str | Path,
                 functions: Mapping[str, UserFunction] | None = None,
                 automata: str | Path | None = None,
                 parameters: ParameterValues = ()) -> None:
        self.vepl = vepl
        self.parameters = parameters
        self.out_dir = Path(out_dir)
        self.functions = functions
        self.automata = Path(automata) if automata is not None else None
        self.host: AutomataHost | None = None
        self.result: MonitorResult | None = None
        self._listeners: list[Callable[[str, float], None]] = []

    def listen(self, listener: Callable[[str, float], None]) -> None:
        """Tell ``listener(name, time)`` of every signal the monitor fires, as it fires (the
        run loop hands them to the fault stage)."""
        self._listeners.append(listener)
        if self.host is not None:
            self.host.listeners.append(listener)

    def start(self, header: StreamHeader) -> None:
        from rei.lang.vepl.document import load_vepl  # noqa: PLC0415
        from rei.runtime.observation.monitor.needs import check_needs  # noqa: PLC0415

        # `rei run` and `rei replay` refuse this earlier; a stream from elsewhere is refused
        # here, before any verdict: never judged on data it does not carry.
        check_needs(load_vepl(self.vepl, self.parameters), header.data, "the stream to carry",
                    "collect that data, or drop the query")
        self.out_dir.mkdir(parents=True, exist_ok=True)
        path = self.automata or generate_automata(self.vepl, self.out_dir / "automata",
                                                  parameters=self.parameters)
        self.host = AutomataHost(load_generated(path), header, self.functions)
        self.host.listeners.extend(self._listeners)

    def feed(self, sample: Sample) -> None:
        if self.host is None:
            raise MonitorError("the monitor was fed a sample before the stream header")
        self.host.feed(sample)

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        if self.host is None:
            raise MonitorError("the monitor was finished before the stream header")
        self.result = self.host.finish(end_time, outcome, reason)
        self.host.log.write_csv(self.out_dir / "events.csv")
