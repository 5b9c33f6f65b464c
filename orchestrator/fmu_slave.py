"""The slave inside an FMU made by ``suscosim export-fmu`` (never imported by suscosim), beside
``suscosim_law.json`` and copies of ``nodes/controller`` and ``cosim/errors.py``. The law is
built when the FMU leaves initialisation; each ``doStep(t, dt)`` calls ``law.step(t, state)``:
force [N], slope dF_d/dv_rel [N·s/m] and extras at t, as in the controller node.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

FMI_VERSION = 2  # export_fmu rewrites this line for an FMI 3.0 FMU
SPEC_FILE = "suscosim_law.json"

if FMI_VERSION == 3:
    from pythonfmu3 import Float64 as Real
    from pythonfmu3 import Fmi3Causality as Causality
    from pythonfmu3 import Fmi3Slave as SlaveBase
    from pythonfmu3 import Fmi3Variability as Variability
else:
    from pythonfmu import Fmi2Causality as Causality
    from pythonfmu import Fmi2Slave as SlaveBase
    from pythonfmu import Fmi2Variability as Variability
    from pythonfmu import Real


class SuscosimLaw(SlaveBase):
    """A suscosim control law for one corner (inputs z_b, v_b, z_w, v_w [, v_damper])."""

    author = "suscosim export-fmu"

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        resources = Path(self.resources)
        if str(resources) not in sys.path:
            sys.path.insert(0, str(resources))  # the embedded nodes/ and cosim/
        spec = json.loads((resources / SPEC_FILE).read_text())
        self.spec = spec
        self.modelName = spec["model_name"]
        self.description = spec["description"]
        self.values: dict[str, float] = {}
        self.law: Any = None
        if FMI_VERSION == 3:  # FMI 3.0 wants its independent variable declared
            self.time = 0.0
            self.register_variable(Real("time", causality=Causality.independent,
                                        variability=Variability.continuous))
        for name in spec["inputs"]:
            self._variable(name, 0.0, Causality.input)
        for name in spec["outputs"]:
            self._variable(name, 0.0, Causality.output)
        for name, value in spec["parameters"].items():
            self._variable(name, float(value), Causality.parameter, Variability.fixed)

    def _variable(self, name: str, value: float, causality: Any, variability: Any = None) -> None:
        self.values[name] = value
        extra = {"variability": variability} if variability is not None else {}
        if FMI_VERSION == 3 and causality == Causality.parameter:
            extra["start"] = value
        self.register_variable(Real(
            name, causality=causality, getter=lambda n=name: self.values[n],
            setter=lambda v, n=name: self.values.__setitem__(n, float(v)),
            **extra), nested=False)

    def exit_initialization_mode(self) -> None:
        from nodes.controller.laws import build_controller

        cfg = dict(self.spec["controller"])
        cfg.update({k: self.values[k] for k in self.spec["parameters"]})
        self.law = build_controller(cfg, 1, float(self.spec["h"]))

    def do_step(self, current_time: float, step_size: float) -> bool:
        import numpy as np

        self.time = float(current_time)
        if self.law is None:  # a master that skipped initialisation mode
            self.exit_initialization_mode()
        state = {n: np.array([self.values[n]]) for n in self.spec["inputs"]}
        out = self.law.step(float(current_time), state)
        produced = {"F_d": out.F_d, "c_eff": out.c_eff, **out.extra}
        for name in self.spec["outputs"]:
            self.values[name] = float(produced[name][0])
        return True
