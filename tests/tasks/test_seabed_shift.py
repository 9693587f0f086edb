"""The seed 004 shift-error script: its nominal path and control against eq. 3 and eq. 6 worked
out here, a small measurement, and its refusal of bad input."""

import numpy as np

from tasks import seabed_shift as ss


def test_nominal_path_is_eq3_of_section_6():
    x, _v = ss.nominal_path(300)
    assert x.shape == (301, 3)
    np.testing.assert_allclose(x[0], [0.0, 0.0, -10.0])
    np.testing.assert_allclose(np.linalg.norm(np.diff(x, axis=0), axis=1), 2.0, atol=1e-12)
    t = 7.0
    g, th = np.pi / 100 * np.cos(np.pi / 100 * t), np.pi / 3 * np.cos(np.pi / 25 * t)
    step = x[8] - x[7]
    np.testing.assert_allclose(
        step, 2 * np.array([np.cos(g) * np.cos(th), np.cos(g) * np.sin(th), np.sin(g)])
    )


def test_control_of_eq6_lands_on_the_target():
    rng = np.random.default_rng(0)
    pos, target = rng.normal(size=(50, 3)), rng.normal(size=(50, 3)) + [3.0, 0.0, 0.0]
    att, dist = ss.control_attitude(target, pos)
    g, th = att[:, 0], att[:, 1]
    e = np.column_stack([np.cos(g) * np.cos(th), np.cos(g) * np.sin(th), np.sin(g)])
    np.testing.assert_allclose(pos + dist[:, None] * e, target, atol=1e-12)


def test_a_small_measurement_reports_both_readings():
    res = ss.measure_shift_error(paths=3, seed=1, steps=4)
    assert set(res) == {"one_attitude", "turning"}
    for r in res.values():
        s = r.summary()
        assert s["produced"] == s["samples"] == 12
        assert np.isfinite([s["median_m"], s["p90_m"], *s["bias_m"], s["stated_rms_m"]]).all()
    again = ss.measure_shift_error(paths=3, seed=1, steps=4)
    assert np.array_equal(again["turning"].error_m, res["turning"].error_m)


def test_bad_arguments_exit_2_with_one_line(capsys):
    assert ss.main(["--paths", "0"]) == 2
    err = capsys.readouterr()
    assert err.out == "" and err.err.count("\n") == 1 and "--paths = 0" in err.err


def test_a_path_draws_the_same_numbers_whatever_the_batch():
    two = ss.measure_shift_error(paths=2, seed=3, steps=3)
    three = ss.measure_shift_error(paths=3, seed=3, steps=3)
    for r in two:
        assert np.array_equal(two[r].error_m, three[r].error_m[:2])
