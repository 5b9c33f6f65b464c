"""The one-process engine (``run.transport = "inprocess"``; the thesis's "purely multi-body"):
the node models stepped in this thread, no bus, in the distributed run's sequential order: per
step the plant's state, each force node's step in registry order, the plant couples the forces,
the sinks (recorder, live fatigue) take every message, the plant integrates to t_{k+1}. Every
message goes through the run's codec (:mod:`cosim.wire`): the tables and fatigue files are the
distributed run's bit for bit (tested). DESIGN.md allows this module, and only it, to import
node modules. Refused (ScenarioError, exit 2): checkpoints, resume/fork, a function node.
"""

from __future__ import annotations

import inspect
import time
from collections.abc import Callable
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import node_kinds as nk
from cosim import schema
from cosim.errors import RunError, ScenarioError, WireError
from cosim.journal import JournalWriter
from cosim.run_settings import RunSettings
from cosim.stepped import Fields, outputs_of
from cosim.wire import MAX_MESSAGE_BYTES, Message, codec, decode, encode
from nodes.plant.models import build_plant_model
from nodes.plant.stepper import PlantStepper
from nodes.recorder.recording import Recording, write_error

PROGRESS_PERIOD_S = 0.1


@dataclass
class EngineResult:
    """The recorder's result, the live fatigue's ``done`` facts (or None), times [s]."""

    recorder: dict[str, Any]
    fatigue: dict[str, Any] | None
    step_wall_s: float  # first step to the last step's outputs (sinks included)
    run_wall_s: float  # first step until the table and fatigue files are written
    sink_s: float = 0.0  # of step_wall_s, the sinks' share
    step_cpu_s: float = 0.0  # this process's CPU time over the steps


def refusal(scenario: dict[str, Any]) -> None:
    """A ScenarioError for what the engine does not run."""
    run = scenario["run"]
    if run.get("checkpoint_every_s"):
        raise ScenarioError("run.checkpoint_every_s", run["checkpoint_every_s"],
                            "0 with run.transport = \"inprocess\" (checkpoints need the "
                            "distributed run: run.transport = \"zenoh\")")
    if run.get("resume"):
        raise ScenarioError("run.transport", "inprocess", "\"zenoh\" to resume or fork a run")
    for name in run["nodes"]:
        impl = nk.implementation(name, scenario)
        if name in (ch.PLANT, ch.RECORDER, ch.FATIGUE) and impl is not nk.kind(name).impl:
            raise ScenarioError(f"{nk.SECTION}.{name}", impl.entry, "the native "
                                f"{name} with run.transport = \"inprocess\"")
        if nk.kind(name).role == nk.COUPLED and name != ch.PLANT and \
                not inspect.isclass(nk.load(impl.entry, f"{nk.SECTION}.{name}")):
            raise ScenarioError(f"{nk.SECTION}.{name}", impl.entry,
                                "a stepped class with run.transport = \"inprocess\" (a "
                                "function node runs on the bus: run.transport = \"zenoh\")")


class _Stepped:
    """A force node's stepped class and its inputs (as :func:`cosim.stepped.run_stepped`)."""

    def __init__(self, name: str, scenario: dict[str, Any]) -> None:
        self.name = name
        self.kind = nk.kind(name)
        self.cls = nk.load(nk.implementation(name, scenario).entry, f"{nk.SECTION}.{name}")
        wanted = getattr(self.cls, "FIELDS", None) or {}
        self.tags = list(nk.inputs(name))
        self.required = {tag: tuple(wanted.get(f"{tag[0]}/{tag[1]}",
                                               schema.required(*tag))) for tag in self.tags}
        self.channels = [c for c in self.kind.writes if c not in ("step", "records")]
        self.node: Any = None

    def close(self) -> None:
        close = getattr(self.node, "close", None)
        if callable(close):
            close()


class Engine:
    def __init__(self, scenario: dict[str, Any],
                 on_progress: Callable[[int, int], None] | None = None) -> None:
        refusal(scenario)
        self.scenario = scenario
        self.run = run = scenario["run"]
        self.settings = RunSettings.of(scenario)
        self.n = int(run["n_steps"])
        self.on_progress = on_progress or (lambda k, n: None)
        self.latest: dict[tuple[str, str], dict[int, Message]] = {}  # last two by step
        self.rec: Recording | None = None
        self.fatigue: Any = None  # the live fatigue's LiveLoads, if any
        self.sink_s = 0.0  # [s] the sinks' time within the steps

    def emit(self, node: str, channel: str, k: int, t: float, data: Any) -> Message:
        """One data message through the codec, as a node's outbox and its consumers do."""
        raw = encode("data", k, t, data)
        if len(raw) > MAX_MESSAGE_BYTES:
            raise RunError(f"{node}/{channel}: a message of {len(raw)} bytes at step {k} "
                           f"(at most {MAX_MESSAGE_BYTES}: split it)")
        try:
            msg = codec(f"{node}/{channel}").decode(raw)
        except WireError as exc:
            raise RunError(f"{node} cannot publish {exc} (did the model diverge?)") from None
        box = self.latest.setdefault((node, channel), {})
        box[k] = msg
        box.pop(k - 2, None)
        t0 = time.perf_counter()
        if self.rec is not None:
            self.rec.record(node, channel, raw, msg)
        sink = self.fatigue
        if sink is not None and node == ch.PLANT and channel in sink.by_channel:
            try:
                sink.take(sink.by_channel[channel], k, t, msg.d)
            except ValueError as exc:
                raise RunError(f"fatigue: {exc}") from None
        self.sink_s += time.perf_counter() - t0
        return msg

    def _inputs(self, node: _Stepped, k: int) -> tuple[float, dict[str, Fields]]:
        """A force node's inputs of step k (and its t: the state's, for an adaptive step)."""
        out: dict[str, Fields] = {}
        t = k * self.settings.h
        for tag, j in self.settings.needs(node.tags, k).items():
            msg = self.latest.get(tag, {}).get(j)
            if msg is None:
                raise RunError(f"{node.name}: no {tag[0]}/{tag[1]} of step {j} (an input the "
                               "one-process engine cannot order before it)")
            missing = [f for f in node.required[tag] if f not in msg.d]
            if missing:
                raise RunError(f"{node.name}: {tag[0]}/{tag[1]} lacks {', '.join(missing)}")
            if tag == (ch.PLANT, ch.STATE) and self.settings.adaptive is not None:
                t = msg.t
            out[f"{tag[0]}/{tag[1]}"] = Fields(msg)
        return t, out

    def execute(self) -> EngineResult:
        run, settings, scenario = self.run, self.settings, self.scenario
        folder = Path(run["dir"])
        names = list(run["nodes"])
        fatigue = None
        if ch.FATIGUE in names:  # (its imports are heavy: only when the run has it)
            from nodes.fatigue.live_sink import LiveLoads

            fatigue = LiveLoads(scenario)
        model = build_plant_model(scenario["vehicle"])
        stepped = [_Stepped(n, scenario) for n in names
                   if nk.kind(n).role == nk.COUPLED and n != ch.PLANT]
        journal: JournalWriter | None = None
        try:
            outputs = [ch.STATE, ch.RESPONSE, *model.loads().keys()]
            info: dict[str, Any] = {ch.PLANT: dict(model.info(), outputs=outputs)}
            info.update({s.name: {"outputs": s.channels} for s in stepped})
            if fatigue is not None:
                info[ch.FATIGUE] = {"outputs": [ch.DAMAGE]}
            info[ch.RECORDER] = {"outputs": [ch.COUPLING]}
            # the start as the nodes get it from the clock: through the codec
            start = decode(encode("start", -1, 0.0, {"n_steps": self.n, "h": run["h"],
                                                     "info": info})).d
            journal = JournalWriter(folder / "journal.msgpack", run["id"])
            rec = self.rec = Recording(scenario, journal, _refuse, live=False)
            rec.begin(self.n, (f"{node}/{c}" for node, i in start["info"].items()
                               if node in nk.producers() for c in i.get("outputs", [])))
            if fatigue is not None:
                fatigue.begin(self.n)
                self.fatigue = fatigue
            for s in stepped:
                s.node = s.cls(scenario, start)
            plant = PlantStepper(model, settings, self.n)
            t0 = last_progress = time.monotonic()
            cpu0 = time.process_time()
            while True:
                k, t, st = plant.begin()
                self.emit(ch.PLANT, ch.STATE, k, t, st)
                forces: dict[str, Message] = {}
                for s in stepped:
                    ts, inputs = self._inputs(s, k)
                    for channel, fields in outputs_of(s.kind, s.node.step(k, ts, inputs),
                                                      k).items():
                        msg = self.emit(s.name, channel, k, ts, fields)
                        if channel == ch.FORCE:
                            forces[s.name] = msg
                for channel, values in plant.couple(forces)():
                    self.emit(ch.PLANT, channel, k, t, values)
                now = time.monotonic()
                if now - last_progress >= PROGRESS_PERIOD_S:
                    last_progress = now
                    journal.flush()
                    self.on_progress(k, self.n)
                if plant.is_last():
                    break
                plant.advance()
            step_wall = time.monotonic() - t0
            step_cpu = time.process_time() - cpu0
            self.on_progress(k, self.n)
            if not rec.complete:
                raise RunError(f"the table is incomplete after step {k}: "
                               f"{rec.gap or 'a channel did not give every step'}")
            journal.close()
            result = rec.finish_table()
            facts = None
            if fatigue is not None:
                if not fatigue.done:
                    raise RunError(f"fatigue: the last load step did not come (step "
                                   f"{fatigue.main.next_k - 1})")
                facts = fatigue.finish()[1]
            return EngineResult(result, facts, step_wall, time.monotonic() - t0, self.sink_s,
                                step_cpu)
        except BaseException as exc:
            table = self.rec.table if self.rec is not None else None
            if journal is not None:
                with suppress(OSError):
                    journal.close()
            if table is not None:
                try:
                    if isinstance(exc, OSError):
                        raise exc
                    table.close()  # the rows that are complete, in place
                except OSError:  # a full disk: the journal is the record
                    table.abandon()
            if isinstance(exc, OSError):  # the journal or the table could not be written
                raise write_error(exc, folder) from None
            raise
        finally:
            for s in stepped:
                s.close()
            model.close()


def _refuse(tag: tuple[str, str], why: str) -> None:
    """A message the recorder would not journal: in one process, a bug to say at once."""
    raise RunError(f"recorder: {tag[0]}/{tag[1]}: {why}")
