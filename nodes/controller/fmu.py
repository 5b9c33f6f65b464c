"""The FMU law: an FMI 2.0 or 3.0 co-simulation FMU as the controller (run with FMPy).

``[controller] law = "fmu"`` with ``fmu`` (path), ``substeps`` [1], ``c_eff`` [0 N·s/m] and
the tables ``inputs`` (FMU input -> one of :data:`INPUT_SIGNALS`), ``outputs`` (FMU output ->
channel; ``F_d`` in N on the body, upward positive, required) and ``fmu_parameters``;
docs/fmi.md gives the keys, defaults and errors. One FMU instance per corner; at step k each
gets the inputs of t_k and steps to t_k + h, its outputs the force of step k (an algebraic
law gives exactly the native f(u(t_k))). :func:`check_fmu` (preflight) refuses a file that is
not a readable FMI 2/3 co-simulation FMU for this platform, or a map naming what the FMU
lacks, with an error naming the file or the key (exit 2); the FMU is instantiated at the
run's first step.
"""

from __future__ import annotations

import atexit
import contextlib
import shutil
import tempfile
import zipfile
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from cosim.config import ConfigReader
from cosim.errors import InputFileError, RunError, ScenarioError
from cosim.safe_open import check_user_file
from nodes.controller.base import BODY_KEYS, Controller, ControlOutput
from nodes.controller.registry import law_builder

#: Our signals an FMU input can be mapped to.
INPUT_SIGNALS = ("z_b", "v_b", "z_w", "v_w", "v_rel", "v_damper", *BODY_KEYS)
#: FMI types of a real number, by FMI version.
REAL_TYPES = ("Real", "Float64", "Float32")
KEYS = ("fmu", "substeps", "c_eff", "inputs", "outputs", "fmu_parameters")


@dataclass
class FmuPlan:
    """What preflight found: the FMU's description and the resolved variable maps."""

    path: Path
    md: Any  # fmpy.model_description.ModelDescription
    inputs: dict[str, str]  # FMU input name -> our signal
    outputs: dict[str, str]  # FMU output name -> our channel
    parameters: dict[str, Any]  # FMU parameter name -> value

    def checkpoint_refusal(self) -> str | None:
        """Why this FMU's state cannot be checkpointed (None when it can): a checkpoint needs
        both ``canGetAndSetFMUstate`` and ``canSerializeFMUstate`` (the state leaves the
        process into the run folder) in the co-simulation description (FMI 2.0 / 3.0)."""
        cs = self.md.coSimulation
        missing = [flag for flag, ok in (("canGetAndSetFMUstate", cs.canGetAndSetFMUstate),
                                         ("canSerializeFMUstate", cs.canSerializeFMUstate))
                   if not ok]
        if not missing:
            return None
        return (f"the FMU {self.path.name} cannot be checkpointed: its modelDescription.xml "
                f"does not declare {' and '.join(missing)} (a resume would restart its "
                "internal state wrong, so it is refused)")


MAX_FMU_BYTES = 1 << 30
"""The most an FMU may unpack to [bytes] (its members' sizes; more is a zip bomb)."""
MAX_FMU_MEMBERS = 10_000
"""The most members an FMU may hold (a real one: a description, binaries, resources)."""
MAX_MEMBER_RATIO = 200
"""The largest inflation of a member over 1 MiB: binaries and XML deflate 2-20 times, zeros
about 1000 times."""


def _check_members(path: Path, zf: zipfile.ZipFile) -> None:
    """From the zip directory, before any byte is inflated: every member inside the FMU's
    folder, at most :data:`MAX_FMU_MEMBERS` of them, none inflating more than
    :data:`MAX_MEMBER_RATIO` times, the whole within :data:`MAX_FMU_BYTES`."""
    total = 0
    infos = zf.infolist()
    if len(infos) > MAX_FMU_MEMBERS:
        raise InputFileError(str(path), f"{len(infos)} members, more than {MAX_FMU_MEMBERS}")
    for info in infos:
        name = info.filename
        if name.startswith("/") or "\\" in name or ":" in name or ".." in name.split("/"):
            raise InputFileError(str(path), f"not an FMU: member {name!r:.80} points outside "
                                            "the FMU's folder")
        if info.file_size > 1 << 20 and info.file_size > MAX_MEMBER_RATIO * max(
                info.compress_size, 1):
            raise InputFileError(str(path), f"member {name!r:.80} inflates {info.compress_size}"
                                            f" bytes to {info.file_size} (more than "
                                            f"{MAX_MEMBER_RATIO} times: a zip bomb?)")
        total += info.file_size
    if total > MAX_FMU_BYTES:
        raise InputFileError(str(path), f"unpacks to {total / 2**20:.0f} MiB, more than "
                                        f"{MAX_FMU_BYTES / 2**20:.0f} MiB (a zip bomb?)")


def _read_description(path: Path) -> Any:
    """The model description of ``path``; every way it can fail is an InputFileError."""
    from fmpy import read_model_description

    if not path.exists():
        raise InputFileError(str(path), "no such FMU file")
    check_user_file(path, "fmu", "controller.fmu")
    if not zipfile.is_zipfile(path):
        raise InputFileError(str(path), "not an FMU: not a zip archive (corrupt or truncated?)")
    try:
        with zipfile.ZipFile(path) as zf:
            if "modelDescription.xml" not in zf.namelist():
                raise InputFileError(str(path), "not an FMU: no modelDescription.xml in the zip")
            _check_members(path, zf)
            bad = zf.testzip()
        if bad is not None:
            raise InputFileError(str(path), f"corrupt FMU: member {bad} fails its CRC check")
        return read_model_description(str(path), validate=True)
    except InputFileError:
        raise
    except Exception as exc:  # zlib, lxml, fmpy validation: all mean a broken FMU
        msg = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputFileError(str(path), f"cannot read the FMU's model description: {msg}") from None


def _variables(md: Any) -> dict[str, Any]:
    return {v.name: v for v in md.modelVariables}


def _names(variables: Mapping[str, Any], causality: str) -> list[str]:
    return sorted(n for n, v in variables.items() if v.causality == causality)


def check_fmu(r: ConfigReader, n_corners: int) -> FmuPlan:
    """Preflight of ``law = "fmu"``: open the FMU, check it and the variable maps."""
    from fmpy import platform, supported_platforms

    path = Path(r.string("fmu"))
    md = _read_description(path)
    if md.fmiVersion not in ("2.0",) and not str(md.fmiVersion).startswith("3."):
        raise InputFileError(str(path), f"FMI {md.fmiVersion} FMU: suscosim runs FMI 2.0 and "
                             "3.0 co-simulation FMUs")
    if md.coSimulation is None:
        kinds = [k for k in ("modelExchange", "scheduledExecution") if getattr(md, k, None)]
        raise InputFileError(str(path), f"a {' / '.join(kinds) or 'non-co-simulation'}-only "
                             "FMU: suscosim needs a co-simulation FMU (export it with "
                             "'Co-Simulation' selected, e.g. FMI CS in Simulink or "
                             "OpenModelica's --fmiType=cs)")
    platforms = supported_platforms(str(path))
    if platform not in platforms:
        raise InputFileError(str(path), f"no binary for this platform ({platform}); the FMU "
                             f"has: {', '.join(platforms) or 'none'}")
    if n_corners > 1 and md.coSimulation.canBeInstantiatedOnlyOncePerProcess:
        raise InputFileError(str(path), f"canBeInstantiatedOnlyOncePerProcess, but this vehicle "
                             f"needs one instance per corner ({n_corners})")
    variables = _variables(md)
    return FmuPlan(path, md, _map_inputs(r, variables), _map_outputs(r, variables),
                   _map_parameters(r, variables))


def _map_table(r: ConfigReader, variables: Mapping[str, Any], causality: str,
               value_ok: Callable[[Any], bool], expected: str) -> dict[str, str]:
    """The ``[controller.<causality>s]`` table (FMU variable -> our signal or channel), each
    entry checked: an FMU variable of that causality, a value ``value_ok`` accepts (else the
    error says ``expected``), a real variable. Empty when the table is absent or empty."""
    names = _names(variables, causality)
    out = {}
    for name, value in r.table(f"{causality}s").items():
        key = f"{causality}s.{name}"
        if name not in variables or variables[name].causality != causality:
            raise ScenarioError(r.key(key), value, f"the name of an {causality} of the FMU; "
                                f"'{name}' is not one (its {causality}s: {names or 'none'})")
        if not value_ok(value):
            raise ScenarioError(r.key(key), value, expected)
        if variables[name].type not in REAL_TYPES:
            raise ScenarioError(r.key(key), name, f"a real (Float64) variable; '{name}' is "
                                f"{variables[name].type}")
        out[str(name)] = str(value)
    return out


def _map_inputs(r: ConfigReader, variables: Mapping[str, Any]) -> dict[str, str]:
    out = _map_table(r, variables, "input", lambda signal: signal in INPUT_SIGNALS,
                     f"one of the signals {list(INPUT_SIGNALS)}")
    # default: the FMU inputs named like one of our signals
    return out or {n: n for n in _names(variables, "input") if n in INPUT_SIGNALS}


def _map_outputs(r: ConfigReader, variables: Mapping[str, Any]) -> dict[str, str]:
    out = _map_table(r, variables, "output",
                     lambda channel: isinstance(channel, str) and channel.isidentifier(),
                     "a channel name (F_d, c_eff, or an identifier for an extra channel)")
    fmu_outputs = _names(variables, "output")
    if not out:  # default: every real output under its own name
        out = {n: n for n in fmu_outputs if variables[n].type in REAL_TYPES and n.isidentifier()}
    if "F_d" not in out.values():
        raise ScenarioError(r.key("outputs"), dict(r.table("outputs")) or None,
                            f"a map with one FMU output -> 'F_d' (the FMU has no output named "
                            f"F_d; its outputs: {fmu_outputs or 'none'})")
    return out


def _map_parameters(r: ConfigReader, variables: Mapping[str, Any]) -> dict[str, Any]:
    out = {}
    settable = sorted(n for n, v in variables.items()
                      if v.causality in ("parameter", "input") and v.variability != "constant")
    for name, value in r.table("fmu_parameters").items():
        key = r.key(f"fmu_parameters.{name}")
        var = variables.get(name)
        if var is None or name not in settable:
            raise ScenarioError(key, value, f"the name of a parameter of the FMU; '{name}' is "
                                f"not one (its parameters: {settable or 'none'})")
        kind = var.type
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if kind == "Boolean":
            ok = isinstance(value, bool)
        elif kind == "String":
            ok = isinstance(value, str)
        elif kind.startswith(("Int", "UInt", "Integer", "Enumeration")):
            ok = number and float(value) == int(value)
        else:
            ok = number and bool(np.isfinite(value))
        if not ok:
            raise ScenarioError(key, value, f"a value of the FMU variable's type ({kind})")
        out[str(name)] = value
    return out


class FmuController(Controller):
    """Runs one FMU instance per corner, one doStep (or ``substeps``) per communication step."""

    fixed_step = True  # the FMU advances by the fixed communication step h

    law = "fmu"

    def __init__(self, n_corners: int, h: float, plan: FmuPlan, substeps: int,
                 c_eff: float) -> None:
        super().__init__(n_corners, h)
        self.plan, self.substeps, self.c_eff_default = plan, substeps, c_eff
        self._instances: list[Any] = []
        self._unzipdir: str | None = None
        variables = _variables(plan.md)
        self._in = [(variables[n].valueReference, s) for n, s in plan.inputs.items()]
        self._out = [(variables[n].valueReference, c) for n, c in plan.outputs.items()]
        self._params = [(variables[n], v) for n, v in plan.parameters.items()]
        self._fmi3 = str(plan.md.fmiVersion).startswith("3.")
        self._messages: deque[str] = deque(maxlen=5)
        self._broken = self._fatal = False

    # ------------------------------------------------------------------ FMI calls
    def _set_real(self, fmu: Any, vrs: list[int], values: list[float]) -> None:
        (fmu.setFloat64 if self._fmi3 else fmu.setReal)(vrs, values)

    def _set_param(self, fmu: Any, var: Any, value: Any) -> None:
        vr = [var.valueReference]
        if var.type in REAL_TYPES:
            self._set_real(fmu, vr, [float(value)])
        elif var.type == "Boolean":
            fmu.setBoolean(vr, [bool(value)])
        elif var.type == "String":
            fmu.setString(vr, [str(value)])
        elif self._fmi3:
            getattr(fmu, f"set{var.type}")(vr, [int(value)])
        else:
            fmu.setInteger(vr, [int(value)])

    def _log(self, *args: Any) -> None:
        """FMI logger (FMI 2: env, instance, status, category, message; FMI 3: env, status,
        category, message): keep the last messages of a warning or worse for the error."""
        status, message = args[-3], args[-1]
        if status >= 1:  # 1 warning, 2 discard, 3 error, 4 fatal
            raw = message.decode("utf-8", "replace") if isinstance(message, bytes) else message
            self._messages.append(str(raw).strip())

    def _failed(self, exc: Exception, what: str) -> RunError:
        self._broken = True
        self._fatal = getattr(exc, "status", None) == 4  # fmi2Fatal / fmi3Fatal
        said = " | ".join(" ".join(m.split()) for m in self._messages if m)[-600:]
        return RunError(f"the FMU {self.plan.path.name} failed {what}: {str(exc).rstrip('.')}"
                        + (f"; it said: {said}" if said else ""))

    def _start(self, t: float, inputs: list[list[float]]) -> None:
        from fmpy import extract, instantiate_fmu

        # the folder is ours before a byte is extracted: close() removes it however the run
        # ends, an extraction that failed half way included
        self._unzipdir = tempfile.mkdtemp(prefix="suscosim_fmu_")
        atexit.register(self.close)
        extract(str(self.plan.path), self._unzipdir)
        for i in range(self.n):
            # logging on: what an FMU says when it fails goes into the error (costs no
            # measurable time per step with a PythonFMU FMU, which says nothing otherwise)
            fmu = instantiate_fmu(self._unzipdir, self.plan.md, fmi_type="CoSimulation",
                                  logger=self._log, debug_logging=True)
            self._instances.append(fmu)
            if self._fmi3:
                fmu.enterInitializationMode(startTime=t)
            else:
                fmu.setupExperiment(startTime=t)
                fmu.enterInitializationMode()
            for var, value in self._params:
                self._set_param(fmu, var, value)
            if self._in:
                self._set_real(fmu, [vr for vr, _ in self._in], inputs[i])
            fmu.exitInitializationMode()

    def close(self) -> None:
        """Terminate and free the FMU instances, remove the extracted FMU (idempotent)."""
        instances, self._instances = self._instances, []
        if self._fatal:  # FMI: after a fatal status no call at all, not even freeInstance
            instances = []
        for fmu in instances:
            if not self._broken:  # after an error FMI allows only freeing the instance
                with contextlib.suppress(Exception):  # best effort at shutdown
                    fmu.terminate()
            # free the instance but keep the library loaded: a PythonFMU binary leaves Python
            # objects that point into it (unloading it made the GC crash later)
            with contextlib.suppress(Exception):
                (fmu.fmi3FreeInstance if self._fmi3 else fmu.fmi2FreeInstance)(fmu.component)
        if self._unzipdir:
            shutil.rmtree(self._unzipdir, ignore_errors=True)
            self._unzipdir = None

    # ------------------------------------------------------------------ checkpoints
    def _refuse_checkpoint(self) -> None:
        from cosim.checkpoint import CheckpointError

        if why := self.plan.checkpoint_refusal():
            raise CheckpointError(why)

    def checkpoint_state(self) -> dict[str, Any]:
        """Every corner's FMU state, serialised by the FMU itself (FMI get + serialize FMU
        state), for a checkpoint. Raises :class:`cosim.checkpoint.
        CheckpointError` (exit 2) naming the FMU when it cannot, never a partial state."""
        blobs: list[bytes] = []
        self._refuse_checkpoint()
        s = "State" if self._fmi3 else "state"  # FMI 3 getFMUState, FMI 2 getFMUstate
        for fmu in self._instances:
            st = getattr(fmu, f"getFMU{s}")()
            blobs.append(bytes(getattr(fmu, f"serializeFMU{s}")(st)))
            getattr(fmu, f"freeFMU{s}")(st)
        return {"fmu": self.plan.path.name, "fmi": str(self.plan.md.fmiVersion),
                "started": bool(blobs), "states": blobs}

    def restore_state(self, state: dict[str, Any], t: float,
                      state_inputs: Mapping[str, np.ndarray]) -> None:
        """Put every corner's FMU back into a :meth:`checkpoint_state` ``state``; ``t`` [s]
        and ``state_inputs`` (the plant's state at the checkpoint) start the instances first."""
        from cosim.checkpoint import CheckpointError

        self._refuse_checkpoint()
        n_saved = len(state.get("states", ()))
        if state.get("fmu") != self.plan.path.name or n_saved not in (0, self.n):
            raise CheckpointError(f"the checkpoint holds the state of {state.get('fmu')!r} for "
                                  f"{len(state.get('states', ()))} corners, not of "
                                  f"{self.plan.path.name} for {self.n}")
        if not state["states"]:
            return  # checkpointed before its first step: nothing started yet
        if not self._instances:
            self._start(float(t), self._signals(state_inputs))
        s, de = ("State", "deserialize") if self._fmi3 else ("state", "deSerialize")
        for fmu, blob in zip(self._instances, state["states"], strict=True):
            st = getattr(fmu, f"{de}FMU{s}")(blob)
            getattr(fmu, f"setFMU{s}")(st)
            getattr(fmu, f"freeFMU{s}")(st)

    # ------------------------------------------------------------------ the law
    def _signals(self, state: Mapping[str, Any]) -> list[list[float]]:
        """Input values per corner, in the order of the input map."""
        cols = [np.broadcast_to(c, (self.n,)) for c in self.inputs(state, [s for _, s in self._in])]
        return [[float(c[i]) for c in cols] for i in range(self.n)]

    def step(self, t: float, state: Mapping[str, np.ndarray]) -> ControlOutput:
        inputs = self._signals(state)
        if not self._instances:
            try:
                self._start(float(t), inputs)
            except Exception as exc:  # FMICallException, a library that does not load
                raise self._failed(exc, "to start") from None
        try:
            return self._step(float(t), inputs)
        except RunError:
            raise
        except Exception as exc:
            raise self._failed(exc, f"at t = {t:g} s") from None

    def _step(self, t: float, inputs: list[list[float]]) -> ControlOutput:
        dt = self.h / self.substeps
        vrs_in = [vr for vr, _ in self._in]
        vrs_out = [vr for vr, _ in self._out]
        values = np.empty((self.n, len(vrs_out)))
        for i, fmu in enumerate(self._instances):
            if vrs_in:
                self._set_real(fmu, vrs_in, inputs[i])
            for j in range(self.substeps):
                result = fmu.doStep(currentCommunicationPoint=float(t) + j * dt,
                                    communicationStepSize=dt)
                if self._fmi3 and result[1]:  # terminateSimulation
                    raise RunError(f"the FMU {self.plan.path.name} asked to terminate at "
                                   f"t = {t + (j + 1) * dt:g} s")
            values[i] = (fmu.getFloat64 if self._fmi3 else fmu.getReal)(vrs_out)
        cols = {ch: values[:, k].copy() for k, (_, ch) in enumerate(self._out)}
        F_d = cols.pop("F_d")
        c_eff = cols.pop("c_eff", np.full(self.n, self.c_eff_default))
        return ControlOutput(F_d=F_d, c_eff=c_eff, extra=cols)


@law_builder("fmu", KEYS)
def _fmu(r: ConfigReader, n: int, h: float) -> Controller:
    """An FMI 2.0 / 3.0 co-simulation FMU (Simulink, Modelica, export-fmu) run with FMPy."""
    plan = check_fmu(r, n)
    substeps = r.number("substeps", 1, lo=1.0)
    if substeps != int(substeps):
        raise ScenarioError(r.key("substeps"), r.cfg["substeps"], "a whole number >= 1")
    c_eff = r.number("c_eff", 0.0, lo=0.0, unit="N·s/m")
    return FmuController(n, h, plan, int(substeps), c_eff)
