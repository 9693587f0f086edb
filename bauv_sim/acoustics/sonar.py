"""The sonar equation of an acoustic modem link: whether a packet is decoded at a range.

Signal-to-noise ratio at the receiver (passive sonar equation; Urick, *Principles of Underwater
Sound*, 3rd ed., 1983, ch. 2):

    SNR = SL - TL(r, f) - (NL(f) + 10 log10 B) + DI                          [dB]

with the source level ``SL`` (dB re 1 uPa at 1 m), the transmission loss ``TL`` (spreading and
absorption), the ambient noise power spectral density ``NL`` at the carrier (dB re 1 uPa^2/Hz)
integrated over the bandwidth ``B`` (Hz) and the receiver's directivity index ``DI`` (dB).

* **Transmission loss** (Stojanovic 2007, eq. 1-2): ``TL = k 10 log10(r / 1 m) + r_km *
  alpha(f)`` with the spreading factor ``k`` (1 cylindrical, 2 spherical, 1.5 "practical") and
  Thorp's absorption (Thorp, "Analytic description of the low-frequency attenuation coefficient",
  J. Acoust. Soc. Am. 42, 270, 1967; in dB/km as Stojanovic 2007 eq. 3, f in kHz):

      alpha(f) = 0.11 f^2 / (1 + f^2) + 44 f^2 / (4100 + f^2) + 2.75e-4 f^2 + 0.003   [dB/km]

* **Ambient noise** (Coates, *Underwater Acoustic Systems*, 1990; Stojanovic 2007 eq. 7), power
  spectral densities in dB re 1 uPa^2/Hz, f in kHz, added in linear power:

      turbulence  10 log N_t  = 17 - 30 log10 f
      shipping    10 log N_s  = 40 + 20 (s - 0.5) + 26 log10 f - 60 log10(f + 0.03)
      wind        10 log N_w  = 50 + 7.5 w^(1/2) + 20 log10 f - 40 log10(f + 0.4)
      thermal     10 log N_th = -15 + 20 log10 f

  with the shipping activity ``s`` in [0, 1] and the wind speed ``w`` in m/s.

* **Detection**: a packet is decoded when its SNR reaches the detection threshold ``DT``. The SNR
  of one packet fluctuates about the sonar equation's value (multipath fading, scintillation);
  with a log-normal fluctuation of standard deviation ``sigma`` dB the probability of success is

      P = Phi((SNR - DT) / sigma)          (a step at SNR = DT when sigma = 0)

  (the Gaussian SNR-margin model of e.g. Stojanovic & Preisig, "Underwater acoustic
  communication channels: propagation models and statistical characterization", IEEE Commun.
  Mag. 47(1), 2009).

Reference: M. Stojanovic, "On the relationship between capacity and distance in an underwater
acoustic communication channel", ACM SIGMOBILE Mob. Comput. Commun. Rev. 11(4), 34-43, 2007.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray
from pydantic import Field
from scipy.special import ndtr

from bauv_sim.config import Config

Array = NDArray[np.float64]


class SonarConfig(Config):
    """The sonar equation of the modems' link (defaults: a mid-frequency acoustic modem of the
    WHOI Micro-Modem class; ``enabled = False``: no packet is lost to it)."""

    enabled: bool = Field(False, description="lose packets by the sonar equation")
    source_level_db: float = Field(185.0, description="source level, dB re 1 uPa at 1 m")
    frequency_khz: float = Field(25.0, gt=0, le=1000, description="carrier frequency, kHz")
    bandwidth_khz: float = Field(5.0, gt=0, le=1000, description="signal bandwidth, kHz")
    spreading_k: float = Field(
        1.5, ge=1, le=2, description="spreading factor (1 cylindrical, 2 spherical)"
    )
    directivity_db: float = Field(0.0, ge=0, description="receiver directivity index, dB")
    detection_threshold_db: float = Field(10.0, description="SNR needed to decode, dB")
    shipping: float = Field(0.5, ge=0, le=1, description="shipping activity (0 low .. 1 high)")
    wind_m_s: float = Field(5.0, ge=0, le=100, description="wind speed at the surface, m/s")
    fading_sigma_db: float = Field(
        0.0, ge=0, description="sd of the SNR's log-normal fluctuation, dB (0: a hard threshold)"
    )


def thorp_absorption_db_per_km(frequency_khz: ArrayLike) -> Array:
    """Thorp's absorption coefficient (module docstring; Stojanovic 2007 eq. 3).

    Args:
        frequency_khz: frequency, any shape, kHz.

    Returns:
        Absorption, same shape, dB/km.
    """
    f2 = np.asarray(frequency_khz, dtype=float) ** 2
    return 0.11 * f2 / (1.0 + f2) + 44.0 * f2 / (4100.0 + f2) + 2.75e-4 * f2 + 0.003


def transmission_loss_db(range_m: ArrayLike, frequency_khz: float, spreading_k: float) -> Array:
    """Spreading and absorption loss ``k 10 log10(r / 1 m) + alpha(f) r / 1000`` (module
    docstring; Stojanovic 2007 eq. 1-2).

    Args:
        range_m: distance, any shape, m (below 1 m the loss is that of 1 m: the source level's
            reference distance).
        frequency_khz: carrier frequency, kHz.
        spreading_k: spreading factor, 1 .. 2.

    Returns:
        Loss, same shape, dB.
    """
    r = np.maximum(np.asarray(range_m, dtype=float), 1.0)
    return spreading_k * 10.0 * np.log10(r) + thorp_absorption_db_per_km(frequency_khz) * r / 1e3


def noise_psd_db(frequency_khz: ArrayLike, shipping: float, wind_m_s: float) -> Array:
    """Ambient noise power spectral density, turbulence + shipping + wind + thermal (module
    docstring; Coates 1990, Stojanovic 2007 eq. 7).

    Args:
        frequency_khz: frequency, any shape, kHz (> 0).
        shipping: shipping activity in [0, 1].
        wind_m_s: wind speed, m/s.

    Returns:
        Noise PSD, same shape, dB re 1 uPa^2/Hz.
    """
    f = np.asarray(frequency_khz, dtype=float)
    lf = np.log10(f)
    nt = 17.0 - 30.0 * lf
    ns = 40.0 + 20.0 * (shipping - 0.5) + 26.0 * lf - 60.0 * np.log10(f + 0.03)
    nw = 50.0 + 7.5 * math.sqrt(wind_m_s) + 20.0 * lf - 40.0 * np.log10(f + 0.4)
    nth = -15.0 + 20.0 * lf
    return 10.0 * np.log10(10 ** (nt / 10) + 10 ** (ns / 10) + 10 ** (nw / 10) + 10 ** (nth / 10))


def snr_db(range_m: ArrayLike, cfg: SonarConfig) -> Array:
    """The sonar equation's SNR at the receiver, ``SL - TL - (NL + 10 log10 B) + DI`` (module
    docstring).

    Args:
        range_m: distance between transmitter and receiver, any shape, m.
        cfg: the link.

    Returns:
        SNR, same shape, dB.
    """
    tl = transmission_loss_db(range_m, cfg.frequency_khz, cfg.spreading_k)
    nl = noise_psd_db(cfg.frequency_khz, cfg.shipping, cfg.wind_m_s)
    band = 10.0 * math.log10(cfg.bandwidth_khz * 1e3)
    return cfg.source_level_db - tl - (nl + band) + cfg.directivity_db


def success_probability(
    snr_db_: ArrayLike, detection_threshold_db: float, fading_sigma_db: float
) -> Array:
    """Probability that a packet is decoded, ``Phi((SNR - DT) / sigma)`` (module docstring).

    Args:
        snr_db_: the sonar equation's SNR, any shape, dB.
        detection_threshold_db: the threshold DT, dB.
        fading_sigma_db: sd of the SNR's fluctuation, dB; 0: 1 where SNR >= DT, else 0.

    Returns:
        Probability, same shape, in [0, 1].
    """
    margin = np.asarray(snr_db_, dtype=float) - detection_threshold_db
    if fading_sigma_db == 0:
        return (margin >= 0).astype(float)
    return ndtr(margin / fading_sigma_db)
