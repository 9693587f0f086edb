"""The sonar equation of the modem link, worked out in the test from the published formulas:
Thorp's absorption (checked against his original dB/kiloyard form), spreading, the Coates /
Stojanovic noise spectra, the SNR and the probability of decoding a packet."""

import math

import numpy as np
import pytest
from scipy import stats

from bauv_sim.acoustics.sonar import (
    SonarConfig,
    noise_psd_db,
    snr_db,
    success_probability,
    thorp_absorption_db_per_km,
    transmission_loss_db,
)
from bauv_sim.config import load_config
from bauv_sim.errors import ConfigError

KYD_PER_KM = 1000.0 / 914.4  # one kiloyard is 914.4 m


def thorp_db_per_kyd(f_khz):
    """Thorp (1967) as he published it, in dB per kiloyard (f in kHz; e.g. Urick 1983 eq. 5.9)."""
    f2 = f_khz**2
    return 0.1 * f2 / (1 + f2) + 40 * f2 / (4100 + f2) + 2.75e-4 * f2 + 0.003


def test_thorp_matches_the_published_kiloyard_form():
    # the dB/km coefficients are the dB/kyd ones times 1.0936 kyd/km, rounded (Stojanovic 2007
    # eq. 3): within 1 % of the original at every frequency of a modem
    f = np.array([0.5, 1, 2, 5, 10, 20, 25, 50, 100])
    ratio = thorp_absorption_db_per_km(f) / (thorp_db_per_kyd(f) * KYD_PER_KM)
    assert np.all(np.abs(ratio - 1) < 0.01)
    # a worked value: at 10 kHz, 0.11*100/101 + 44*100/4200 + 0.0275 + 0.003 = 1.1870 dB/km
    assert thorp_absorption_db_per_km(10.0) == pytest.approx(1.18703, abs=1e-5)


def test_transmission_loss_is_spreading_plus_absorption():
    # 2 km at 10 kHz, practical spreading: 15 log10(2000) + 2 * 1.18703 dB
    expected = 15 * math.log10(2000) + 2 * 1.1870297
    assert transmission_loss_db(2000.0, 10.0, 1.5) == pytest.approx(expected, abs=1e-5)
    # spherical spreading is 6.02 dB per doubling of range; at 1 Hz only Thorp's constant
    # 0.003 dB/km absorbs over the extra 100 m
    d = transmission_loss_db(200.0, 1e-3, 2.0) - transmission_loss_db(100.0, 1e-3, 2.0)
    assert d == pytest.approx(20 * math.log10(2) + 0.003 * 0.1, abs=1e-6)


def coates_noise_db(f, s, w):
    """Coates (1990) as Stojanovic (2007) eq. 7 states it, summed in linear power."""
    parts = [
        17 - 30 * math.log10(f),
        40 + 20 * (s - 0.5) + 26 * math.log10(f) - 60 * math.log10(f + 0.03),
        50 + 7.5 * math.sqrt(w) + 20 * math.log10(f) - 40 * math.log10(f + 0.4),
        -15 + 20 * math.log10(f),
    ]
    return 10 * math.log10(sum(10 ** (p / 10) for p in parts))


@pytest.mark.parametrize(
    "f,s,w", [(0.1, 0.5, 0), (1, 1, 10), (10, 0.5, 0), (25, 0, 5), (100, 0, 0)]
)
def test_noise_matches_coates(f, s, w):
    assert noise_psd_db(f, s, w) == pytest.approx(coates_noise_db(f, s, w), abs=1e-9)


def test_noise_worked_value_at_10_khz():
    # 10 kHz, s = 0.5, no wind: wind term 50 + 20 - 40 log10(10.4) = 29.32 dB dominates
    # (turbulence -13, shipping 66 - 60 log10(10.03) = 5.92, thermal 5):
    # 10 log10(855.6 + 3.9 + 3.2 + 0.05) = 29.35 dB
    assert noise_psd_db(10.0, 0.5, 0.0) == pytest.approx(29.355, abs=0.005)


def test_snr_is_the_sonar_equation():
    cfg = SonarConfig(
        source_level_db=170, frequency_khz=12, bandwidth_khz=4, directivity_db=3, wind_m_s=8
    )
    r = np.array([50.0, 800.0, 3000.0])
    a = thorp_db_per_kyd(12.0) * KYD_PER_KM  # independent of the code's coefficients (1 %)
    tl = 15 * np.log10(r) + a * r / 1000
    nl = coates_noise_db(12, 0.5, 8) + 10 * math.log10(4000)
    expected = 170 - tl - nl + 3
    np.testing.assert_allclose(snr_db(r, cfg), expected, atol=0.01 * a * 3 + 1e-9)


def test_success_probability_is_the_normal_margin():
    snr = np.array([0.0, 5.0, 10.0, 12.0, 20.0])
    np.testing.assert_allclose(
        success_probability(snr, 10.0, 3.0), stats.norm.cdf((snr - 10) / 3), atol=1e-12
    )
    np.testing.assert_array_equal(success_probability(snr, 10.0, 0.0), [0, 0, 1, 1, 1])


@pytest.mark.parametrize(
    "field,value", [("frequency_khz", 0), ("spreading_k", 2.5), ("shipping", 1.5)]
)
def test_bad_sonar_names_the_field(field, value):
    with pytest.raises(ConfigError, match=field):
        load_config(SonarConfig, overrides=[f"{field}={value}"])
