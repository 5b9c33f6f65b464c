"""Ride metrics against numbers known independently (sines, ISO 2631-1 Table 3 values)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from nodes.recorder.ride_metrics import (
    improvement,
    metric_values,
    resample_to,
    ride_summary,
    ride_table,
    run_metrics,
    sample_rate,
    thesis_band_rms,
    wk_response,
)

from .ride_oracle import jerk, matlab_periodogram, rms

# ISO 2631-1:1997 Table 3, weighting Wk (factor x 1000) at nominal one-third-octave frequencies
ISO_WK = {
    0.5: 418, 1.0: 482, 2.0: 531, 4.0: 967, 5.0: 1039, 6.3: 1054,
    10.0: 988, 16.0: 768, 20.0: 636, 31.5: 405, 50.0: 246, 100.0: 88.7,
}  # fmt: skip


def sine(f, amp, fs, duration):
    t = np.arange(0.0, duration, 1.0 / fs)
    return t, amp * np.sin(2 * np.pi * f * t)


def test_rms_of_a_sine():
    _, x = sine(3.0, 2.0, 500.0, 10.0)
    assert rms(x) == pytest.approx(2.0 / np.sqrt(2.0), rel=1e-6)


@pytest.mark.parametrize(("f", "gain"), sorted(ISO_WK.items()))
def test_wk_gain_matches_iso_table(f, gain):
    assert abs(wk_response(f)) * 1000 == pytest.approx(gain, rel=5e-3)


@pytest.mark.parametrize("f", [1.0, 4.0, 10.0])
def test_wk_weighted_rms_of_a_sine(f):
    fs = 500.0
    t, a = sine(f, 1.0, fs, 30.0)
    expected = ISO_WK[f] / 1000 / np.sqrt(2)
    wk = metric_values({"t": t, "plant/response/a_b": a})["a_b_wk_rms"][0]
    assert wk == pytest.approx(expected, rel=0.01)


def test_working_space_and_dynamic_tyre_load():
    z_b = np.array([0.00, 0.01, -0.01, 0.00])
    z_w = np.array([0.00, 0.03, -0.04, 0.01])
    # deflection z_w - z_b = 0, 0.02, -0.03, 0.01 -> used space 0.05 m
    t = np.arange(4) * 0.002
    m = metric_values({"t": t, "plant/state/z_b": z_b, "plant/state/z_w": z_w})
    assert m["sws"] == (pytest.approx(50.0), "mm", "SWS [mm]")
    t, F = sine(2.0, 300.0, 500.0, 5.0)
    m = metric_values({"t": t, "tyre_road/force/F_t": 5000.0 + F})
    assert m["dtl_rms"][0] == pytest.approx(300 / np.sqrt(2), rel=1e-6)


def test_jerk_peak_of_a_sine_is_w3_x0():
    # thesis Eq 2.1: x = x0 sin(wt) has peak jerk w^3 x0
    fs, f, x0 = 2000.0, 2.0, 0.01
    w = 2 * np.pi * f
    t, _ = sine(f, 1.0, fs, 2.0)
    a = -x0 * w**2 * np.sin(w * t)
    assert np.max(np.abs(jerk(a, fs))) == pytest.approx(w**3 * x0, rel=1e-3)


def test_sample_rate_rejects_gaps():
    assert sample_rate(np.arange(0, 1, 0.002)) == pytest.approx(500.0)
    with pytest.raises(ValueError, match="uniformly"):
        sample_rate(np.array([0.0, 0.002, 0.004, 0.010, 0.012]))


def make_run(scale):
    fs, duration = 500.0, 10.0
    t = np.arange(0.0, duration, 1.0 / fs)
    a0 = scale * np.sin(2 * np.pi * 1.0 * t)
    return {
        "k": np.arange(t.size),
        "t": t,
        "plant/response/a_b[0]": a0,
        "plant/response/a_b[1]": 0.5 * a0,
        "plant/state/z_b": 0.01 * np.sin(2 * np.pi * t),
        "plant/state/z_w": np.zeros_like(t),
        "tyre_road/force/F_t": 5000.0 + scale * 100.0 * np.sin(2 * np.pi * 5 * t),
    }


def test_run_metrics_and_ride_table():
    passive, semi = make_run(1.0), make_run(0.8)
    m = run_metrics(passive)
    assert m["a_b[0] RMS full band [m/s2]"] == pytest.approx(1 / np.sqrt(2), rel=1e-6)
    assert m["a_b[0] RMS 0-20 Hz [m/s2]"] == pytest.approx(1 / np.sqrt(2), rel=1e-3)
    assert m["a_b[1] RMS 0-20 Hz [m/s2]"] == pytest.approx(0.5 / np.sqrt(2), rel=1e-3)
    assert m["a_b[1] RMS 0-16 Hz [m/s2]"] == pytest.approx(0.5 / np.sqrt(2), rel=1e-3)
    assert m["SWS [mm]"] == pytest.approx(20.0, rel=1e-3)
    assert m["DTL RMS [N]"] == pytest.approx(100 / np.sqrt(2), rel=1e-6)
    text = ride_table({"passive": passive, "TSS1": semi})
    lines = text.splitlines()
    assert lines[0].split() == ["metric", "passive", "TSS1", "%"]
    assert lines[2].startswith("a_b[0] RMS 0-20 Hz [m/s2]")  # the headline comes first
    row = next(line for line in lines if line.startswith("a_b[0] RMS 0-20 Hz [m/s2]"))
    assert row.split()[-1] == "20.0"  # (1 - 0.8) / 1 x 100
    dtl = next(line for line in lines if line.startswith("DTL RMS"))
    assert dtl.split()[-1] == "20.0"
    # the baseline can be any run: TSS1 as baseline makes passive 25 % worse
    text = ride_table({"passive": passive, "TSS1": semi}, baseline="TSS1")
    row = next(line for line in text.splitlines()
               if line.startswith("a_b[0] RMS full band [m/s2]"))
    assert row.split()[-1] == "-25.0"
    assert improvement(0.8981, 0.7112) == pytest.approx(20.81, abs=0.01)  # Table 5.3 TSS1


# ------------------------------------------------------------ the thesis's metric


def test_a_500_hz_record_passes_through_the_resampling_unchanged():
    rng = np.random.default_rng(3)
    t = np.arange(0, 5000) * 0.002
    x = rng.standard_normal(t.size)
    np.testing.assert_array_equal(resample_to(t, x), x)
    f, P = matlab_periodogram(x, 500.0)
    assert thesis_band_rms(t, x, (0.0, 20.0)) == pytest.approx(
        float(np.sqrt(np.trapezoid(P[f <= 20.0], f[f <= 20.0]))), rel=1e-12)


def test_periodogram_is_matlabs_default():
    # nfft = max(256, 2^nextpow2(N)), no detrend: a constant shows at 0 Hz; the integral over
    # 0..fs/2 of a sine's PSD is its mean square (Parseval with the one-sided doubling)
    fs, n = 500.0, 1000
    f, P = matlab_periodogram(np.full(n, 2.0), fs)
    assert f.size == 1024 // 2 + 1 and f[1] == pytest.approx(fs / 1024)
    assert P[0] == pytest.approx(4.0 * n / fs)  # |sum x|^2 / (fs N), DC not doubled
    t = np.arange(n) / fs
    f, P = matlab_periodogram(np.sin(2 * np.pi * 50.0 * t), fs)
    assert np.sum(P) * (f[1] - f[0]) == pytest.approx(0.5, rel=1e-3)


@pytest.mark.parametrize("fs", [500.0, 1000.0, 2000.0])
def test_white_noise_band_rms_scales_with_the_band(fs):
    # white noise of variance s^2 at the 500 Hz of the metric: 0-20 Hz holds sqrt(20/250) s;
    # a faster run's noise spread over fs/2 keeps its density s^2/(fs/2) after the low-pass
    rng = np.random.default_rng(11)
    sigma, duration = 1.7, 200.0
    t = np.arange(0.0, duration, 1.0 / fs)
    x = sigma * rng.standard_normal(t.size)
    for band in ((0.0, 20.0), (0.0, 16.0), (0.0, 100.0)):
        expected = sigma * np.sqrt((band[1] - band[0]) / (fs / 2))
        assert thesis_band_rms(t, x, band) == pytest.approx(expected, rel=0.03)


@pytest.mark.parametrize("fs", [200.0, 500.0, 2000.0, 2000.0 / 0.6])
def test_sine_of_known_amplitude_at_any_rate(fs):
    t = np.arange(0.0, 20.0, 1.0 / fs)
    x = 0.7 * np.sin(2 * np.pi * 3.0 * t) + 0.2 * np.sin(2 * np.pi * 45.0 * t)
    assert thesis_band_rms(t, x, (0.0, 20.0)) == pytest.approx(0.7 / np.sqrt(2), rel=1e-3)
    assert thesis_band_rms(t, x, (0.0, 16.0)) == pytest.approx(0.7 / np.sqrt(2), rel=1e-3)
    if fs >= 500.0:
        assert thesis_band_rms(t, x, (30.0, 60.0)) == pytest.approx(0.2 / np.sqrt(2), rel=2e-3)


def test_chatter_above_250_hz_does_not_fold_into_the_band():
    # a 2 kHz record with a 490 Hz tone (500 - 490 = 10 Hz if aliased without a filter)
    fs = 2000.0
    t = np.arange(0.0, 20.0, 1.0 / fs)
    ride = 0.5 * np.sin(2 * np.pi * 1.2 * t)
    x = ride + 3.0 * np.sin(2 * np.pi * 490.0 * t)
    assert thesis_band_rms(t, x) == pytest.approx(0.5 / np.sqrt(2), rel=2e-3)
    naive = x[::4]  # what dropping samples would count
    assert thesis_band_rms(t[::4], naive) > 2.0


def test_wk_and_jerk_on_the_resampled_signal_do_not_depend_on_the_rate():
    f, amp = 4.0, 1.0
    w = 2 * np.pi * f
    out = {}
    for fs in (500.0, 2000.0):
        t = np.arange(0.0, 30.0, 1.0 / fs)
        a = amp * np.sin(w * t)
        m = metric_values({"t": t, "plant/response/a_b": a})
        out[fs] = (m["a_b_wk_rms"][0], m["jerk_b_rms"][0])
    assert out[500.0][0] == pytest.approx(ISO_WK[4.0] / 1000 / np.sqrt(2), rel=0.01)
    assert out[500.0][1] == pytest.approx(w * amp / np.sqrt(2), rel=0.01)
    assert out[2000.0][0] == pytest.approx(out[500.0][0], rel=1e-3)
    assert out[2000.0][1] == pytest.approx(out[500.0][1], rel=1e-3)


def test_the_headline_ignores_chatter_the_full_band_counts():
    # the same 1 Hz ride at 2 kHz, with and without 600 Hz switching chatter
    fs = 2000.0
    t = np.arange(0.0, 10.0, 1.0 / fs)
    ride = np.sin(2 * np.pi * 1.0 * t)
    chatter = 0.8 * np.sin(2 * np.pi * 600.0 * t)
    clean = metric_values({"t": t, "plant/response/a_b": ride})
    noisy = metric_values({"t": t, "plant/response/a_b": ride + chatter})
    assert noisy["a_b_rms"][0] == pytest.approx(clean["a_b_rms"][0], rel=1e-3)
    assert noisy["a_b_rms_full"][0] == pytest.approx(np.sqrt(0.5 + 0.32), rel=1e-3)
    assert clean["a_b_rms"][1] == "m/s2"


def test_ride_summary_lists_every_metric_of_every_run():
    passive, semi = make_run(1.0), make_run(0.8)
    out = ride_summary({"passive": passive, "TSS1": semi})
    assert out["baseline"] == "passive" and out["band_hz"] == [0.0, 20.0]
    assert out["fs_metric_hz"] == 500.0
    assert [r["name"] for r in out["runs"]] == ["passive", "TSS1"]
    p, s = (r["metrics"] for r in out["runs"])
    assert set(p) == set(s) == set(out["units"]) == set(out["labels"])
    assert p["a_b[0]_rms"] == pytest.approx(1 / np.sqrt(2), rel=1e-3)
    assert s["a_b[0]_rms"] == pytest.approx(0.8 / np.sqrt(2), rel=1e-3)
    assert out["units"]["sws"] == "mm" and p["sws"] == pytest.approx(20.0, rel=1e-3)
    assert out["runs"][0]["change_pct"] == {}
    assert out["runs"][1]["change_pct"]["a_b[0]_rms"] == pytest.approx(20.0, abs=1e-6)
    assert out["labels"]["a_b[0]_rms"] == "a_b[0] RMS 0-20 Hz [m/s2]"
    with pytest.raises(ValueError, match="baseline"):
        ride_summary({"passive": passive}, baseline="nope")


# ------------------------------------------------- real runs of the lumped quarter car


@pytest.mark.integration
def test_the_same_run_at_2_ms_and_at_half_a_ms_gives_the_same_headline(tmp_path, capsys):
    """Passive lumped QVM on the Ch. 5 random road (white road velocity: the input with the
    most high-frequency content), run by the real CLI at h = 2 ms (500 Hz, no resampling) and
    0.5 ms (2 kHz, resampled): the headline 0-20 Hz body RMS agrees within 1 %. Jacobian
    coupling, so the physics has converged at both steps (with the thesis's zero-order hold
    the 2 ms run itself is 3.4 % high against the SciPy reference, a coupling error and not a
    metric one; REPRODUCTION.md Ch. 5)."""
    from cosim.table import read_table
    from orchestrator import ride

    from ..conftest import ROOT, suscosim

    scenario = ROOT / "scenarios" / "ch5_qvm_passive_random.toml"
    dirs = {}
    for h in (0.002, 0.0005):
        out = tmp_path / f"h{h * 1e3:g}ms"
        res = suscosim("run", str(scenario), "--out", str(out), "--mode", "monolithic",
                       "--quiet", "--set", f"run.h={h}", "--set", 'run.coupling="jacobian"',
                       "--set", "run.t_end=6.0", "--set", "run.stall_timeout_s=120.0",
                       timeout=300.0)  # a loaded machine can starve a node for > 5 s
        assert res.returncode == 0, res.stderr + res.stdout
        dirs[h] = out
    tables = {h: read_table(d / "table.parquet") for h, d in dirs.items()}
    assert sample_rate(tables[0.002]["t"]) == pytest.approx(500.0)
    assert sample_rate(tables[0.0005]["t"]) == pytest.approx(2000.0)
    m = {h: metric_values(tab) for h, tab in tables.items()}
    coarse, fine = m[0.002]["a_b_rms"][0], m[0.0005]["a_b_rms"][0]
    assert coarse > 0.1  # a real ride, not an empty record
    assert fine == pytest.approx(coarse, rel=0.01)
    assert m[0.0005]["a_b_rms_0_16"][0] == pytest.approx(m[0.002]["a_b_rms_0_16"][0], rel=0.01)
    # the 2 ms run's headline is the periodogram of the record as it is (no resampling)
    a = tables[0.002]["plant/response/a_b"]
    f, P = matlab_periodogram(np.asarray(a, dtype=float), 500.0)
    assert coarse == pytest.approx(float(np.sqrt(np.trapezoid(P[f <= 20], f[f <= 20]))),
                                   rel=1e-12)
    # and suscosim ride --json reports the same headline
    assert ride.main([str(dirs[0.002]), str(dirs[0.0005]), "--json"]) == 0
    runs = json.loads(capsys.readouterr().out)["runs"]
    assert [r["metrics"]["a_b_rms"] for r in runs] == pytest.approx([coarse, fine], rel=1e-12)


@pytest.mark.integration
def test_the_headline_of_a_tss3_run_at_half_a_ms_is_the_thesis_metric_of_that_run(tmp_path,
                                                                               capsys):
    """Issue #13: a TSS3 (MR damper, constant-current switching) run at h = 0.5 ms: the headline
    body RMS of `suscosim ride --json` is the thesis's computation of the same record, done
    here independently: resample to 500 Hz (scipy.signal.resample_poly, 1 of every 4, with the
    metric's anti-aliasing Kaiser window; scipy's default window differs by 0.04 %), MATLAB's
    default one-sided periodogram (rectangular window, nfft = 2^nextpow2(N), no detrend),
    sqrt(trapz) over 0-20 Hz selected by frequency."""
    from scipy.signal import periodogram, resample_poly

    from cosim.table import read_table
    from orchestrator import ride

    from ..conftest import ROOT, suscosim

    out = tmp_path / "tss3"
    res = suscosim("run", str(ROOT / "scenarios" / "ch5_qvm_tss3_random.toml"), "--out",
                   str(out), "--mode", "monolithic", "--quiet", "--set", "run.h=0.0005",
                   "--set", "run.t_end=4.0", "--set", "run.stall_timeout_s=120.0",
                   timeout=300.0)
    assert res.returncode == 0, res.stderr + res.stdout
    tab = read_table(out / "table.parquet")
    assert sample_rate(tab["t"]) == pytest.approx(2000.0)
    a = np.asarray(tab["plant/response/a_b"], dtype=float)
    from nodes.recorder import ride_metrics as rm

    x = resample_poly(a, 1, 4, window=("kaiser", rm._AA_KAISER_BETA))
    nfft = 1 << int(np.ceil(np.log2(x.size)))
    f, P = periodogram(x, fs=500.0, window="boxcar", nfft=nfft, detrend=False,
                       scaling="density")
    band = f <= 20.0
    thesis = float(np.sqrt(np.trapezoid(P[band], f[band])))
    assert ride.main([str(out), "--json"]) == 0
    headline = json.loads(capsys.readouterr().out)["runs"][0]["metrics"]["a_b_rms"]
    assert thesis > 0.05
    assert headline == pytest.approx(thesis, rel=1e-9)
