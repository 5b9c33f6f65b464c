"""The FMU law on real FMUs (made by export-fmu with PythonFMU / pythonfmu3, run by FMPy):
it equals the native law, its maps and parameters work, and every bad FMU is named (exit 2)."""

from __future__ import annotations

import shutil
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from cosim import scenario as sc
from cosim.errors import InputFileError, RunError, ScenarioError
from nodes.controller.laws import build_controller
from orchestrator.export_fmu import export_fmu

from ..conftest import ROOT, suscosim

TSS1 = ROOT / "scenarios" / "ch5_qvm_tss1_random.toml"
TSS3 = ROOT / "scenarios" / "ch5_qvm_tss3_random.toml"


@pytest.fixture(scope="module")
def fmus(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("fmus")
    out = {}
    for key, path, fmi in (("tss1", TSS1, 2), ("tss1_fmi3", TSS1, 3), ("tss3", TSS3, 2)):
        out[key] = folder / f"{key}.fmu"
        export_fmu(sc.load(path), out[key], fmi=fmi)
    return out


def random_states(n_corners: int, steps: int, seed: int = 4):
    rng = np.random.default_rng(seed)
    for _ in range(steps):
        yield {"z_b": rng.normal(0, .01, n_corners), "v_b": rng.normal(0, .3, n_corners),
               "z_w": rng.normal(0, .01, n_corners), "v_w": rng.normal(0, .6, n_corners)}


def assert_same_as_native(fmu_cfg, native_cfg, h, steps=300, n=4, swap=False):
    fmu = build_controller(fmu_cfg, n, h)
    native = build_controller(native_cfg, n, h)
    try:
        for k, s in enumerate(random_states(n, steps)):
            a = fmu.step(k * h, s)
            seen = dict(s, v_b=s["v_w"], v_w=s["v_b"]) if swap else s
            b = native.step(k * h, seen)
            np.testing.assert_array_equal(a.F_d, b.F_d)
            np.testing.assert_array_equal(a.c_eff, b.c_eff)
            for key, value in b.extra.items():
                np.testing.assert_array_equal(a.extra[key], value, err_msg=key)
    finally:
        fmu.close()


@pytest.mark.parametrize("key", ["tss1", "tss1_fmi3"])
def test_exported_tss1_fmu_equals_the_native_law_bit_for_bit(fmus, key):
    # doubles cross the FMI boundary unchanged and the FMU runs the same Python arithmetic
    assert_same_as_native({"law": "fmu", "fmu": str(fmus[key])}, {"law": "tss1"}, 0.002)


def test_exported_mr_law_with_internal_state_equals_the_native_law(fmus):
    # TSS3: the MR damper's fluid dynamics integrated in substeps between calls, inside the FMU
    assert_same_as_native({"law": "fmu", "fmu": str(fmus["tss3"])},
                          sc.load(TSS3)["controller"], 0.0005, steps=150, n=1)


def test_fmu_parameters_and_maps(fmus):
    path = str(fmus["tss1"])
    # a parameter set before initialisation changes the law like the scenario key would
    assert_same_as_native({"law": "fmu", "fmu": path, "fmu_parameters": {"c_hard": 3000.0}},
                          {"law": "tss1", "c_hard": 3000.0}, 0.002, steps=100)
    # inputs mapped by name: the FMU's v_b fed with our v_w and back = the law on swapped speeds
    swapped = {"z_b": "z_b", "v_b": "v_w", "z_w": "z_w", "v_w": "v_b"}
    assert_same_as_native({"law": "fmu", "fmu": path, "inputs": swapped}, {"law": "tss1"},
                          0.002, steps=100, swap=True)
    # an output renamed into an extra channel; no c_eff output -> the constant c_eff
    ctl = build_controller({"law": "fmu", "fmu": path, "c_eff": 1234.0,
                            "outputs": {"F_d": "F_d", "state": "hard"}}, 1, 0.002)
    out = ctl.step(0.0, {"z_b": [0.0], "v_b": [0.2], "z_w": [0.0], "v_w": [0.0]})
    ctl.close()
    assert out.F_d[0] == pytest.approx(-473.6) and out.c_eff[0] == 1234.0
    assert out.extra == {"hard": np.array([1.0])}


# ---------------------------------------------------------------------------- bad FMUs


def rezip(src: Path, dst: Path, drop: str = "", xml=None) -> Path:
    """Copy an FMU, leaving out members under ``drop`` and rewriting modelDescription.xml."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            if drop and item.filename.startswith(drop):
                continue
            data = zin.read(item.filename)
            if item.filename == "modelDescription.xml" and xml is not None:
                data = xml(data.decode()).encode()
            zout.writestr(item, data)
    return dst


def model_exchange_only(xml: str) -> str:
    start = xml.index("<CoSimulation")
    end = xml.index("/>", start) + 2
    return xml[:start] + '<ModelExchange modelIdentifier="suscosim_tss1"/>' + xml[end:]


def test_bad_fmu_files_are_named(fmus, tmp_path):
    good = fmus["tss1"]
    truncated = tmp_path / "truncated.fmu"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    flipped = tmp_path / "flipped.fmu"
    data = bytearray(good.read_bytes())
    with zipfile.ZipFile(good) as zf:  # a byte inside the compressed model description
        info = zf.getinfo("modelDescription.xml")
    data[info.header_offset + 30 + len(info.filename) + 40] ^= 0xFF
    flipped.write_bytes(bytes(data))
    text = tmp_path / "notes.fmu"
    text.write_text("not a zip")
    no_md = rezip(good, tmp_path / "no_md.fmu", drop="modelDescription.xml")
    me = rezip(good, tmp_path / "me.fmu", xml=model_exchange_only)
    win = rezip(good, tmp_path / "win.fmu", drop="binaries/linux64")
    cases = [
        (tmp_path / "missing.fmu", "no such FMU file"),
        (text, "not a zip archive"),
        (truncated, "not a zip archive"),
        (flipped, "corrupt FMU"),
        (no_md, "no modelDescription.xml"),
        (me, "modelExchange-only FMU"),
        (win, "no binary for this platform (linux64); the FMU has: win64"),
    ]
    for path, message in cases:
        with pytest.raises(InputFileError) as err:
            build_controller({"law": "fmu", "fmu": str(path)}, 1, 0.002)
        assert err.value.path == str(path) and message in str(err.value), (path, str(err.value))


@pytest.mark.parametrize(
    ("extra", "key", "words"),
    [
        ({"inputs": {"v_body": "v_b"}}, "controller.inputs.v_body", "its inputs: ['v_b', 'v_w'"),
        ({"inputs": {"v_b": "speed"}}, "controller.inputs.v_b", "one of the signals"),
        ({"outputs": {"force": "F_d"}}, "controller.outputs.force", "its outputs: ['F_d',"),
        ({"outputs": {"c_eff": "c_eff"}}, "controller.outputs", "one FMU output -> 'F_d'"),
        ({"fmu_parameters": {"c_hrad": 1.0}}, "controller.fmu_parameters.c_hrad",
         "its parameters: ['c_hard', 'c_soft'"),
        ({"fmu_parameters": {"c_hard": "hard"}}, "controller.fmu_parameters.c_hard", "(Real)"),
        ({"substeps": 1.5}, "controller.substeps", "whole number"),
        ({"preset": "lumped"}, "controller.preset", "one of the keys"),
    ],
)
def test_bad_maps_name_the_key_and_the_fmu_variables(fmus, extra, key, words):
    with pytest.raises(ScenarioError) as err:
        build_controller({"law": "fmu", "fmu": str(fmus["tss1"]), **extra}, 1, 0.002)
    assert err.value.key == key and words in str(err.value), str(err.value)


def test_cli_exit_2_names_a_bad_fmu_and_a_missing_variable(fmus, tmp_path):
    corrupt = tmp_path / "corrupt.fmu"
    corrupt.write_bytes(fmus["tss1"].read_bytes()[:5000])
    scenario = tmp_path / "s.toml"
    scenario.write_text(fmu_scenario(str(fmus["tss1"])))
    for sets, words in (
        ([f'controller.fmu="{tmp_path / "nope.fmu"}"'], "nope.fmu: no such FMU file"),
        ([f'controller.fmu="{corrupt}"'], "corrupt.fmu: not an FMU: not a zip archive"),
        (['controller.inputs={v_body="v_b"}'], "scenario key 'controller.inputs.v_body'"),
    ):
        res = suscosim("run", str(scenario), "--quiet", "--mode", "monolithic",
                       *[a for s in sets for a in ("--set", s)])
        assert res.returncode == 2, res.stderr + res.stdout
        assert words in res.stderr and "Traceback" not in res.stderr, res.stderr


def fmu_scenario(path: str) -> str:
    """The ch5 TSS1 scenario with its law replaced by ``law = "fmu"`` on ``path``."""
    text = TSS1.read_text()
    return text[: text.index("\n[controller]") + 1] + f'[controller]\nlaw = "fmu"\nfmu = "{path}"\n'


def test_export_refuses_what_it_cannot_make(tmp_path, fmus):
    fmu_toml = tmp_path / "fmu.toml"
    fmu_toml.write_text(fmu_scenario(str(fmus["tss1"])))
    for args, words in (
        ([str(TSS1), "--set", 'controller.law="pnr"'], "export-fmu makes one corner's FMU"),
        ([str(TSS1), "--set", 'controller.law="tss9"'], "scenario key 'controller.law'"),
        ([str(fmu_toml)], "an FMU already"),
    ):
        res = suscosim("export-fmu", *args, "--out", str(tmp_path / "x.fmu"))
        assert res.returncode == 2 and words in res.stderr, res.stderr + res.stdout
    res = suscosim("export-fmu", str(TSS1), "--out", str(tmp_path / "law.zip"))
    assert res.returncode == 2 and "must end in .fmu" in res.stderr, res.stderr
    assert not list(tmp_path.glob("*.fmu")) and not list(tmp_path.glob("*.zip"))


USER_LAW = '''
from nodes.controller.registry import control_law


@control_law("test_export_user_law")
def law(v_rel, *, c: float = 900.0):
    """Linear c v_rel."""
    return c * v_rel, c
'''


def test_export_embeds_a_user_law_and_a_curve(tmp_path, monkeypatch):
    (tmp_path / "my_fmu_law.py").write_text(USER_LAW)
    curve = tmp_path / "curve.csv"
    curve.write_text("v_rel,F_d\n-0.5,-1500\n0.0,0\n0.5,700\n")
    scenario = sc.load(TSS1)
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    for name, cfg, expected in (
        ("user", {"law": "my_fmu_law:law", "c": 1100.0}, 1100.0 * 0.25),
        ("curve", {"law": "passive_curve", "curve": str(curve)}, 700.0 * 0.5),
    ):
        with monkeypatch.context() as m:
            m.syspath_prepend(str(tmp_path))
            spec = export_fmu(dict(scenario, controller=cfg), tmp_path / f"{name}.fmu")
        sys.modules.pop("my_fmu_law", None)  # the FMU must bring its own copy...
        moved = shutil.move(tmp_path / f"{name}.fmu", elsewhere / f"{name}.fmu")
        if name == "curve":
            curve.unlink()  # ... and the curve's points, not its path
        ctl = build_controller({"law": "fmu", "fmu": str(moved)}, 1, 0.002)
        res = ctl.step(0.0, {"z_b": [0.0], "v_b": [0.0], "z_w": [0.0], "v_w": [0.25]})
        ctl.close()
        assert res.F_d[0] == pytest.approx(expected), (name, spec)
    sys.modules.pop("my_fmu_law", None)


FAILING_LAW = '''
from nodes.controller.registry import control_law


@control_law("test_failing_fmu_law")
def law(t, v_rel, *, c: float = 900.0):
    """Fails after 10 ms."""
    if t > 0.01:
        raise ValueError("the law gave up at t > 10 ms")
    return c * v_rel, c
'''


def test_an_fmu_that_fails_is_a_run_error_with_what_it_said(fmus, tmp_path, monkeypatch):
    # a parameter the law refuses: the FMU fails to start, and says why
    ctl = build_controller({"law": "fmu", "fmu": str(fmus["tss1"]),
                            "fmu_parameters": {"c_hard": 100.0}}, 1, 0.002)
    s = {"z_b": [0.0], "v_b": [0.0], "z_w": [0.0], "v_w": [0.1]}
    with pytest.raises(RunError, match=r"tss1.fmu failed to start: fmi2ExitInitializationMode.*"
                                       r"controller.c_hard.*100"):
        ctl.step(0.0, s)
    ctl.close()
    # a law that raises while stepping
    (tmp_path / "failing_fmu_law.py").write_text(FAILING_LAW)
    with monkeypatch.context() as m:
        m.syspath_prepend(str(tmp_path))
        export_fmu(dict(sc.load(TSS1), controller={"law": "failing_fmu_law:law"}),
                   tmp_path / "failing.fmu")
    sys.modules.pop("failing_fmu_law", None)
    ctl = build_controller({"law": "fmu", "fmu": str(tmp_path / "failing.fmu")}, 1, 0.002)
    with pytest.raises(RunError, match=r"failing.fmu failed at t = 0.012 s: fmi2DoStep.*"
                                       r"the law gave up"):
        for k in range(10):
            ctl.step(k * 0.002, s)
    ctl.close()
    sys.modules.pop("failing_fmu_law", None)


def test_damper_velocity_law_exports_with_v_damper_and_matches(tmp_path):
    cfg = {"law": "tss1", "preset": "realistic", "velocity": "damper"}
    spec = export_fmu(dict(sc.load(TSS1), controller=cfg), tmp_path / "dv.fmu")
    assert spec["inputs"] == ["z_b", "v_b", "z_w", "v_w", "v_damper"]
    fmu = build_controller({"law": "fmu", "fmu": str(tmp_path / "dv.fmu"),
                            "velocity": "damper"}, 1, 0.002)
    native = build_controller(cfg, 1, 0.002)
    try:
        for k, s in enumerate(random_states(1, 100)):
            s["v_damper"] = 0.6 * (s["v_w"] - s["v_b"]) + 0.01
            a, b = fmu.step(k * 0.002, s), native.step(k * 0.002, s)
            np.testing.assert_array_equal(a.F_d, b.F_d)
            # the slope handed to the plant goes through the same motion-ratio conversion
            np.testing.assert_array_equal(fmu.plant_slope(a.c_eff, s),
                                          native.plant_slope(b.c_eff, s))
    finally:
        fmu.close()
