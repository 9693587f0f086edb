"""``acoustics/sound-speed``: the cost of a sound-speed mismatch against closed forms (a sea of
one speed other than the nominal: every range scales by ``c_nom / c_true``), the profile-known
navigator exact without noise and carrying only the device's error with it, the experiment end
to end without NaN, 1 vs 2 workers bit for bit, bad input."""

import json
import math

import numpy as np
import pytest

from bauv_sim.config import load_config
from tasks.acoustics.run import exact, links, passage, run_block
from tasks.acoustics.scenario import SoundSpeedScenario
from tasks.core.runner import run
from tests.tasks.refusal import assert_refused


def _no_nan(text: str) -> dict:
    def refuse(c):
        raise AssertionError(f"{c} in metrics.json")

    return json.loads(text, parse_constant=refuse)


def test_one_speed_sea_scales_every_range_by_the_speed_ratio():
    """In a sea of 1530 m/s, a device at 1500 m/s measures ``r * 1500 / 1530`` along the
    straight ray: the modem's error is ``slant (k - 1)``, the USBL's horizontal error ``|rel_h|
    |k - 1|`` (the direction is right), ``k = 1500 / 1530``; the profile-known navigator is
    exact."""
    scn = load_config(
        SoundSpeedScenario, overrides=["sound.kind=isovelocity", "sound.speed_m_s=1530"]
    )
    got = exact(scn)
    k = 1500.0 / 1530.0
    sender, receiver = links(scn)
    slant = np.linalg.norm(receiver - sender, axis=-1)
    np.testing.assert_allclose(got["modem_error_m"][:, 0], slant * (k - 1), rtol=1e-9)
    np.testing.assert_allclose(got["modem_error_m"][:, 1:], 0.0, atol=1e-6)
    transceiver, pos = passage(scn)
    rel = pos - transceiver
    np.testing.assert_allclose(
        got["usbl_horizontal_m"][:, 0], np.hypot(rel[:, 0], rel[:, 1]) * (1 - k), rtol=1e-9
    )
    np.testing.assert_allclose(got["usbl_horizontal_m"][:, 1:], 0.0, atol=1e-6)
    assert got["usbl_present"].all() and got["modem_present"].all()


@pytest.mark.slow
def test_profile_known_is_exact_and_nominal_pays_the_profile():
    scn = load_config(SoundSpeedScenario)
    got = exact(scn)
    assert got["usbl_present"].all() and got["modem_present"].all()
    assert np.abs(got["usbl_error_3d_m"][:, 2]).max() < 1e-5
    assert np.abs(got["modem_error_m"][:, 2]).max() < 1e-6
    # The harmonic-mean correction removes most of the nominal speed's error, not the bending.
    for key in ("usbl_horizontal_m", "modem_error_m"):
        nominal, harmonic = np.abs(got[key][:, 0]), np.abs(got[key][:, 1])
        assert np.all(harmonic < 0.2 * nominal)
    # Munk's sea is faster than 1500 m/s at these depths: nominal ranges are short, by about
    # (1 - 1500 / c_h) of the range, c_h the speed between the depths (>= 1540 m/s here).
    sender, receiver = links(scn)
    slant = np.linalg.norm(receiver - sender, axis=-1)
    ratio = -got["modem_error_m"][:, 0] / slant
    assert np.all((ratio > 1 - 1500 / 1540) & (ratio < 1 - 1500 / 1549))


@pytest.mark.slow
def test_profile_known_modem_error_is_the_devices_own():
    """With the profile known, the range error is seed 003's (uniform +-0.1 m plus a 0.025 m
    bias: mean 0.025 m, standard deviation 0.1 / sqrt 3), made in nominal metres: the navigator
    turns it into true metres by the speed ratio ``slant / (c_nom T)`` of the link (the
    systematic error of the nominal range gives ``c_nom T``). Mean within 4 standard errors,
    standard deviation within 4 of its own, bound to 1e-4 m (the ratio is the chord's, the
    inversion's slope the ray's)."""
    scn = load_config(SoundSpeedScenario)
    sender, receiver = links(scn)
    slant = np.linalg.norm(receiver - sender, axis=-1)
    ratio = slant / (slant + exact(scn)["modem_error_m"][:, 0])
    b = run_block(scn, 3, tuple(range(120)))
    assert b["modem_present"].all()
    e = (b["modem_error_m"][..., 2] / ratio).ravel()
    sd = 0.1 / math.sqrt(3)
    assert abs(e.mean() - 0.025) < 4 * sd / math.sqrt(e.size)
    assert e.std() == pytest.approx(sd, rel=4 * math.sqrt(1 / (2 * e.size)))
    assert np.abs(e - 0.025).max() <= 0.1 + 1e-4 and np.abs(e - 0.025).max() > 0.099


@pytest.mark.slow
def test_a_small_batch_writes_metrics_and_tables_without_nan(tmp_path):
    out, summary = run(
        "acoustics/sound-speed", n_runs=4, seed=1, out_dir=tmp_path / "run", progress=False
    )
    m = _no_nan((out / "metrics.json").read_text())
    assert m["experiment"] == "acoustics/sound-speed" and m["n_runs"] == 4
    assert set(m["usbl"]["methods"]) == {"nominal", "harmonic", "profile"}
    nominal, known = m["usbl"]["methods"]["nominal"], m["usbl"]["methods"]["profile"]
    assert nominal["systematic_max_m"] > 10 and known["systematic_max_m"] < 1e-5
    assert nominal["horizontal"]["samples"] == 4 * m["usbl"]["fixes"]
    assert len(m["modem"]) == 15
    assert "nan" not in (out / "tables.md").read_text().lower()
    for name in ("sound-speed.png", "sound-speed.pdf"):
        assert (out / name).is_file(), name
    assert "Modem range error" in summary.text and "USBL position error" in summary.text


@pytest.mark.slow
def test_one_and_two_workers_give_the_same_bytes(tmp_path):
    overrides = ["runner.block_size=1", "usbl.fixes=11", "report.figures=false"]
    args = dict(n_runs=4, seed=9, overrides=overrides)
    one, _ = run("acoustics/sound-speed", out_dir=tmp_path / "one", progress=False, **args)
    two, _ = run(
        "acoustics/sound-speed", out_dir=tmp_path / "two", workers=2, progress=False, **args
    )
    assert (one / "metrics.json").read_bytes() == (two / "metrics.json").read_bytes()


@pytest.mark.slow
@pytest.mark.parametrize(
    ("setting", "pattern"),
    [
        ("modem.receiver_depths_m=[10, -1]", "modem.receiver_depths_m"),
        ("sound.kind=table", "depths_m = ()"),
        ("sound.temperatures_c=[10]", "temperatures_c = (10.0,): not used"),
        ("usbl.fixes=1", "usbl.fixes"),
    ],
)
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, setting, pattern):
    assert_refused(tmp_path, "acoustics/sound-speed", "--set", setting, pattern=pattern)
