"""``suscosim export-fmu SCENARIO.toml --out LAW.fmu [--fmi 2|3]``: the scenario's control law
as an FMI co-simulation FMU for one corner (docs/fmi.md). Inputs ``z_b``, ``v_b``, ``z_w``,
``v_w`` [m, m/s] (and ``v_damper``); outputs ``F_d`` [N on the body, upward +], ``c_eff``
[N·s/m] and the law's extras; parameters: its numeric settings. The FMU carries the law's
Python source (needs Python 3 with numpy). Exit 2 on a bad scenario, a law not of one corner,
``law = "fmu"``, or an output not ending in ``.fmu``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import re
import shutil
import sys
import tempfile
from pathlib import Path
from typing import Any

from cosim import channels as ch
from cosim import scenario as sc
from cosim.errors import InputFileError, ScenarioError

ROOT = Path(__file__).resolve().parents[1]
SLAVE_TEMPLATE = Path(__file__).with_name("fmu_slave.py")
SPEC_FILE = "suscosim_law.json"  # = fmu_slave.SPEC_FILE (not imported: it needs pythonfmu)


def _law_module_file(law: str) -> Path | None:
    if ":" not in law:
        return None
    module = importlib.import_module(law.partition(":")[0])
    if module.__name__.startswith("nodes.controller"):
        return None
    path = Path(getattr(module, "__file__", "") or "")
    if path.name == "__init__.py" or "." in module.__name__ or path.suffix != ".py":
        raise ScenarioError("controller.law", law, "a law in a single-file top-level module "
                            "(export-fmu embeds that one file)")
    return path


def law_interface(scenario: dict[str, Any]) -> dict[str, Any]:
    """The FMU's interface: controller table, h, inputs, outputs, parameters."""
    import numpy as np

    from nodes.controller.laws import PassiveCurveController, build_controller
    from nodes.controller.registry import FunctionLaw

    cfg = dict(scenario["controller"])
    h = float(scenario["run"]["h"])
    law = cfg.get("law")
    if law == "fmu":
        raise ScenarioError("controller.law", law, "a native law (this one is an FMU already)")
    try:
        ctl = build_controller(cfg, 1, h)
    except ScenarioError as exc:
        if exc.key == "controller.law" and "corners" in exc.expected:
            raise ScenarioError(exc.key, exc.value, "a per-corner law: export-fmu makes one "
                                f"corner's FMU ({exc.expected})") from None
        raise
    if isinstance(ctl, PassiveCurveController) and "curve" in cfg:  # the FMU carries the
        cfg.pop("curve")                                              # points, not the path
        cfg["points"] = [[float(v), float(f)] for v, f in zip(ctl.curve.v, ctl.curve.F,
                                                                strict=True)]
    inputs = list(ch.STATE_FIELDS) + (["v_damper"] if ctl.velocity == "damper" else [])
    probe = ctl.step(0.0, {name: np.zeros(1) for name in inputs})  # which extras the law records
    outputs = ["F_d", "c_eff", *probe.extra]
    settings = ctl.settings if isinstance(ctl, FunctionLaw) else cfg
    taken = set(inputs) | set(outputs) | {"time"}
    parameters = {k: float(v) for k, v in settings.items() if isinstance(v, int | float)
                  and not isinstance(v, bool) and k not in taken}
    return {"controller": cfg, "h": h, "inputs": inputs, "outputs": outputs,
            "parameters": parameters, "velocity": ctl.velocity}


def _stage(folder: Path, spec: dict[str, Any], module: str, fmi: int, user_file: Path | None,
           ) -> list[Path]:
    text = SLAVE_TEMPLATE.read_text()
    text = text.replace("FMI_VERSION = 2  #", f"FMI_VERSION = {fmi}  #", 1)
    if fmi == 3:  # pythonfmu3 finds the slave by the text 'class X(Fmi3Slave)'
        text = text.replace("SlaveBase", "Fmi3Slave")
    (folder / f"{module}.py").write_text(text)
    (folder / SPEC_FILE).write_text(json.dumps(spec, indent=2))
    files = [folder / SPEC_FILE]
    controller = folder / "nodes" / "controller"
    controller.mkdir(parents=True)
    (folder / "nodes" / "__init__.py").write_text("")
    for src in sorted((ROOT / "nodes" / "controller").glob("*.py")):
        if src.name not in ("node.py", "fmu.py"):  # the bus shell, the FMU runner
            shutil.copy2(src, controller / src.name)
    (folder / "cosim").mkdir()
    for name in ("__init__.py", "errors.py"):
        shutil.copy2(ROOT / "cosim" / name, folder / "cosim" / name)
    files += [folder / "nodes", folder / "cosim"]
    if user_file is not None:
        shutil.copy2(user_file, folder / user_file.name)
        files.append(folder / user_file.name)
    return files


def export_fmu(scenario: dict[str, Any], out: Path | str, fmi: int = 2,
               name: str | None = None) -> dict[str, Any]:
    out = Path(out)
    if out.suffix != ".fmu":
        raise InputFileError(str(out), "the FMU to write must end in .fmu")
    spec = law_interface(scenario)
    law = str(spec["controller"]["law"])
    model_name = name or "suscosim_" + re.sub(r"\W", "_", law)
    if not re.fullmatch(r"[A-Za-z_]\w*", model_name):
        raise ScenarioError("--name", model_name, "a C identifier (letters, digits, _)")
    spec["model_name"] = model_name
    spec["description"] = (f"suscosim control law '{law}' of scenario "
                           f"'{scenario['run'].get('name', '?')}' (one corner, h = {spec['h']:g} s)"
                           f"; inputs {', '.join(spec['inputs'])} (SI), outputs F_d (N, on the "
                           "body, upward +), c_eff (N s/m)")
    spec["fmi"] = fmi
    module = f"suscosim_law_fmi{fmi}"
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.touch()
    except OSError as exc:
        raise InputFileError(str(out), f"cannot write the FMU ({exc.strerror or exc})") from None
    if fmi == 3:
        from pythonfmu3.builder import FmuBuilder
    else:
        from pythonfmu.builder import FmuBuilder
    saved_path = list(sys.path)
    with tempfile.TemporaryDirectory(prefix="suscosim_fmu_") as tmp:
        folder = Path(tmp)
        files = _stage(folder, spec, module, fmi, _law_module_file(law))
        try:
            built = FmuBuilder.build_FMU(folder / f"{module}.py", dest=folder / "out",
                                         project_files=files)
            shutil.move(str(built), str(out))  # the builders differ in how they take a dest
        except BaseException:
            out.unlink(missing_ok=True)  # no half-written FMU left behind
            raise
        finally:  # the builder imports the slave by name and extends sys.path: undo both
            sys.modules.pop(module, None)
            sys.path[:] = saved_path
    from fmpy import read_model_description

    read_model_description(str(out), validate=True)  # what we wrote is a valid FMU
    return spec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="suscosim export-fmu",
                                 description="the scenario's control law as an FMI "
                                             "co-simulation FMU")
    ap.add_argument("scenario", help="scenario TOML file (its [controller] table)")
    ap.add_argument("--out", required=True, help="FMU to write, e.g. tss1.fmu")
    ap.add_argument("--set", action="append", metavar="KEY=VALUE",
                    help="override a scenario value, e.g. --set controller.c_hard=2500")
    ap.add_argument("--fmi", choices=("2", "3"), default="2", help="FMI version [2]")
    ap.add_argument("--name", help="model name / identifier [suscosim_<law>]")
    args = ap.parse_args(argv)
    scenario = sc.load(args.scenario, list(args.set or []))
    out = Path(args.out)
    spec = export_fmu(scenario, out, fmi=int(args.fmi), name=args.name)
    print(f"suscosim export-fmu: {out} (FMI {args.fmi}.0 co-simulation, model "
          f"{spec['model_name']}): law '{spec['controller']['law']}', h = {spec['h']:g} s")
    print(f"  inputs:     {', '.join(spec['inputs'])}")
    print(f"  outputs:    {', '.join(spec['outputs'])}")
    print("  parameters: " + (", ".join(f"{k} = {v:g}" for k, v in spec["parameters"].items())
                             or "-"))
    if spec["velocity"] == "damper":
        print("  velocity = 'damper': run it with velocity = \"damper\" (c_eff is per v_damper)")
    return 0
