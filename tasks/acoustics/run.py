"""The runs of ``acoustics/sound-speed``: USBL fixes and modem ranges through the sea's profile,
turned into positions and ranges by two navigators.

* **nominal**: the navigator assumes the devices' nominal speed and straight rays: a USBL fix
  is ``transceiver + r (cos b sin a, cos b cos a, sin b)`` (:func:`nav.angles.
  rel_from_range_azimuth_elevation`), a modem range is the measured one;
* **profile**: the navigator knows the profile: the travel time ``r / c_nom`` is traced back
  along the arrival direction (:func:`nav.acoustics.source_from_arrival`), and a modem travel
  time becomes the horizontal range between the two known depths
  (:func:`nav.acoustics.range_from_travel_time`), hence the slant range.

The devices are :class:`bauv_sim.sensors.usbl.Usbl` and :class:`bauv_sim.sensors.modem.Modem`
in the true medium (:meth:`bauv_sim.acoustics.SoundSpeedConfig.propagation`): every run draws
their errors from its own streams.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bauv_sim.sensors.errors import AngleErrorConfig, LengthErrorConfig
from bauv_sim.sensors.modem import Modem, ModemConfig
from bauv_sim.sensors.usbl import Usbl, UsblConfig
from bauv_sim.truth import Truth
from nav.acoustics import (
    Isovelocity,
    LayeredMedium,
    range_from_travel_time,
    source_from_arrival,
)
from nav.angles import rel_from_range_azimuth_elevation
from tasks.acoustics.scenario import SoundSpeedScenario

Array = NDArray[np.float64]

METHODS = ("nominal", "profile")
"""The navigators, in the order of the last axis of the block's arrays."""


def _truth(pos: Array) -> Truth:
    """A still truth record at positions ``pos`` (1, k, 3), one second apart."""
    k = pos.shape[1]
    zeros = np.zeros_like(pos)
    return Truth(
        np.arange(k, dtype=float), pos, zeros, zeros, np.zeros((1, k)), np.zeros((1, k, 2)), zeros
    )


def medium(scn: SoundSpeedScenario, nominal_m_s: float) -> LayeredMedium | Isovelocity:
    """The sea's true medium (the devices' own speed when the scenario gives no profile)."""
    true = scn.sound.propagation()
    if true is None:
        return Isovelocity(nominal_m_s)
    assert isinstance(true, LayeredMedium | Isovelocity)
    return true


def passage(scn: SoundSpeedScenario) -> tuple[Array, Array]:
    """The transceiver (3,) and the transponder's positions along the passage (k, 3), m."""
    u = scn.usbl
    east = np.linspace(-u.half_length_m, u.half_length_m, u.fixes)
    pos = np.column_stack(
        [east, np.full(u.fixes, u.closest_approach_m), np.full(u.fixes, -u.depth_m)]
    )
    return np.array([0.0, 0.0, -u.transceiver_depth_m]), pos


def links(scn: SoundSpeedScenario) -> tuple[Array, Array]:
    """Sender and receiver positions of every modem link (g, 3), receiver-depth-major, m."""
    m = scn.modem
    depth, horizontal = np.meshgrid(m.receiver_depths_m, m.horizontal_ranges_m, indexing="ij")
    receiver = np.column_stack([horizontal.ravel(), np.zeros(depth.size), -depth.ravel()])
    sender = np.tile([0.0, 0.0, -m.sender_depth_m], (depth.size, 1))
    return sender, receiver


def usbl_errors(
    scn: SoundSpeedScenario, cfg: UsblConfig, seed: int, runs: tuple[int, ...]
) -> dict[str, Array]:
    """Position errors of both navigators' USBL fixes.

    Returns:
        ``horizontal_m`` and ``error_3d_m`` (n, k, 2) (0 where absent), ``present`` (n, k, 2).
    """
    transceiver, pos = passage(scn)
    true = medium(scn, cfg.sound_speed_m_s)
    s = Usbl(cfg, transceiver, seed, runs, "usbl", propagation=true).sample(
        _truth(pos[None]), np.arange(len(pos))
    )
    rae = s.values
    nominal = transceiver + rel_from_range_azimuth_elevation(rae)
    known = source_from_arrival(
        true, transceiver, rae[..., 1], rae[..., 2], rae[..., 0] / cfg.sound_speed_m_s
    )
    est = np.stack([nominal, known], axis=-2)  # (n, k, 2, 3)
    err = est - pos[None, :, None, :]
    present = s.produced[..., None] & np.all(np.isfinite(est), axis=-1)
    err = np.where(present[..., None], err, 0.0)
    return {
        "horizontal_m": np.hypot(err[..., 0], err[..., 1]),
        "error_3d_m": np.linalg.norm(err, axis=-1),
        "present": present,
    }


def modem_errors(
    scn: SoundSpeedScenario, cfg: ModemConfig, seed: int, runs: tuple[int, ...]
) -> dict[str, Array]:
    """Slant-range errors of both navigators' modem ranges.

    Returns:
        ``error_m`` (n, g, 2) (0 where absent), ``present`` (n, g, 2).
    """
    sender, receiver = links(scn)
    true = medium(scn, cfg.sound_speed_m_s)
    s = Modem(cfg, seed, runs, "modem", propagation=true).sample(
        _truth(sender[None]), _truth(receiver[None]), np.arange(len(sender))
    )
    slant = np.linalg.norm(receiver - sender, axis=-1)
    depth_a, depth_b = -sender[:, 2], -receiver[:, 2]
    meas = np.where(s.produced, s.values, 0.0)
    horizontal = range_from_travel_time(true, depth_a, depth_b, meas / cfg.sound_speed_m_s)
    known = np.hypot(horizontal, depth_b - depth_a)
    est = np.stack([meas, known], axis=-1)
    present = s.produced[..., None] & np.isfinite(est)
    return {"error_m": np.where(present, est - slant[:, None], 0.0), "present": present}


def run_block(scn: SoundSpeedScenario, seed: int, runs: tuple[int, ...]) -> dict[str, Array]:
    """One block of runs: the USBL's and the modem's errors per run and navigator."""
    usbl = usbl_errors(scn, scn.usbl.device, seed, runs)
    modem = modem_errors(scn, scn.modem.device, seed, runs)
    return {
        "usbl_horizontal_m": usbl["horizontal_m"],
        "usbl_error_3d_m": usbl["error_3d_m"],
        "usbl_present": usbl["present"],
        "modem_error_m": modem["error_m"],
        "modem_present": modem["present"],
    }


def exact(scn: SoundSpeedScenario) -> dict[str, Array]:
    """The same without the devices' errors (the systematic cost of the profile): the devices
    with error-free ranges and angles and no losses, one run (shape without the run axis)."""
    usbl_cfg = scn.usbl.device.model_copy(
        update={
            "range": LengthErrorConfig(),
            "azimuth": AngleErrorConfig(),
            "elevation": AngleErrorConfig(),
            "dropout_probability": 0.0,
        }
    )
    modem_cfg = scn.modem.device.model_copy(
        update={"range": LengthErrorConfig(), "dropout_probability": 0.0, "outages_s": ()}
    )
    usbl = usbl_errors(scn, usbl_cfg, 0, (0,))
    modem = modem_errors(scn, modem_cfg, 0, (0,))
    return {
        "usbl_horizontal_m": usbl["horizontal_m"][0],
        "usbl_error_3d_m": usbl["error_3d_m"][0],
        "usbl_present": usbl["present"][0],
        "modem_error_m": modem["error_m"][0],
        "modem_present": modem["present"][0],
    }
