"""The acoustic network's channel: the TDMA schedule, the reception time of a moving receiver
and the arrivals that meet at a receiver (see :mod:`bauv_sim.acoustics.network`, whose module
docstring states the model; the batched network and the online device both use these)."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from bauv_sim.errors import ConfigError
from nav.acoustics import Propagation

if TYPE_CHECKING:
    from bauv_sim.acoustics.network import AcousticNetworkConfig

Array = NDArray[np.float64]

FIXED_POINT_ITERATIONS = 6
"""Iterations of the reception time's fixed point (module docstring)."""


def slot_senders(cfg: AcousticNetworkConfig, vehicles: Sequence[str]) -> list[list[int]]:
    """The senders of each slot, as indices into ``vehicles`` (module docstring: schedule).

    Raises:
        ConfigError: naming ``order`` for an unknown or repeated vehicle, ``slot_s`` when the
            slots do not fit in the cycle, ``clocks`` for a clock of an unknown vehicle.
    """
    names = list(vehicles)
    if len(set(names)) != len(names) or len(names) < 2:
        raise ConfigError(f"network: vehicles {names}: need two or more distinct names")
    for name in cfg.clocks:
        if name not in names:
            raise ConfigError(
                f"network.clocks: {name!r} is not a vehicle (vehicles: {', '.join(names)})"
            )
    entries = cfg.order or tuple(names)
    slots, seen = [], set()
    for entry in entries:
        group = []
        for name in entry.split("+"):
            if name not in names:
                raise ConfigError(
                    f"network.order: {name!r} is not a vehicle (vehicles: {', '.join(names)})"
                )
            if name in seen:
                raise ConfigError(f"network.order: {name!r} has more than one slot")
            seen.add(name)
            group.append(names.index(name))
        slots.append(group)
    if len(slots) * cfg.slot_s > cfg.period_s + 1e-9:
        raise ConfigError(
            f"network.slot_s = {cfg.slot_s:g}: {len(slots)} slots of it do not fit in "
            f"period_s = {cfg.period_s:g}"
        )
    return slots


def schedule(
    cfg: AcousticNetworkConfig, vehicles: Sequence[str], first_s: float, last_s: float
) -> tuple[NDArray[np.intp], Array]:
    """The transmissions with a local time in ``[first_s, last_s]``, in schedule order.

    Returns:
        ``(sender, local_s)``: sender indices into ``vehicles`` and local transmit times (s),
        shape (q,) each, ordered by time, then by the sender's place in its slot.
    """
    slots = slot_senders(cfg, vehicles)
    senders, times = [], []
    c = max(0, math.floor((first_s - cfg.start_s) / cfg.period_s))
    while True:
        t0 = cfg.start_s + c * cfg.period_s
        if t0 > last_s:
            break
        for s, group in enumerate(slots):
            T = t0 + s * cfg.slot_s
            if first_s <= T <= last_s:
                senders += group
                times += [T] * len(group)
        c += 1
    return np.asarray(senders, dtype=np.intp), np.asarray(times, dtype=float)


def reception_time(
    propagation: Propagation,
    source_world_m: Array,
    t_tx_s: Array,
    receiver_at: Callable[[Array], Array],
) -> tuple[Array, Array]:
    """Solve ``t_rx = t_tx + tau(source, receiver(t_rx))`` by fixed-point iteration (module
    docstring).

    Args:
        propagation: the true medium.
        source_world_m: transmitter position at ``t_tx_s``, shape (..., 3), m, world ENU.
        t_tx_s: true transmit times, shape (...), s.
        receiver_at: the receiver's position (shape (..., 3), m) at true times (shape (...)).

    Returns:
        ``(t_rx_s, receiver_world_m)``: the reception time (s) and the receiver's position there
        (m), shapes (...) and (..., 3).
    """
    t = t_tx_s
    for _ in range(FIXED_POINT_ITERATIONS):
        p = receiver_at(t)
        t = t_tx_s + propagation.eigenray(source_world_m, p).travel_time_s
    return t, receiver_at(t)


def interpolate_positions(t_grid_s: Array, positions_world_m: Array, t_s: Array) -> Array:
    """Positions at any times, linear between grid samples (extrapolated from the end segments).

    Args:
        t_grid_s: sample times, shape (k,), s, increasing, k >= 2.
        positions_world_m: positions, shape (n or 1, k, 3), m.
        t_s: query times, shape (n, M), s.

    Returns:
        Positions, shape (n, M, 3), m.
    """
    n = t_s.shape[0]
    pos = positions_world_m
    if pos.shape[0] != n:
        pos = np.broadcast_to(pos, (n, *pos.shape[1:]))
    k = t_grid_s.shape[0]
    idx = np.clip(np.searchsorted(t_grid_s, t_s, side="right") - 1, 0, k - 2)
    t0 = t_grid_s[idx]
    w = (t_s - t0) / (t_grid_s[idx + 1] - t0)
    p0 = np.take_along_axis(pos, idx[..., None], axis=1)
    p1 = np.take_along_axis(pos, idx[..., None] + 1, axis=1)
    return p0 + w[..., None] * (p1 - p0)


def neighbour_gaps(
    times: Array, arrivals: NDArray[np.bool_], own: NDArray[np.bool_], packet_s: float
) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Which arrivals at one receiver collide, and which meet the receiver's own transmission.

    Args:
        times: arrival and own transmission start times, shape (n, M), s (any order).
        arrivals: the columns that are arrivals that interfere, shape (n, M).
        own: the columns that are the receiver's own transmissions, shape (n, M).
        packet_s: packet duration, s.

    Returns:
        ``(collided, half_duplex)``, shape (n, M): an arrival with another arrival closer than
        ``packet_s``; an arrival closer than ``packet_s`` to an own transmission (their
        intervals of ``packet_s`` overlap). False elsewhere.
    """
    order = np.argsort(times, axis=1, kind="stable")
    st = np.take_along_axis(times, order, axis=1)
    out = []
    for mask in (arrivals, own):
        # an infinite time (a packet never sent) is never near anything: inf - inf is NaN
        sm = np.take_along_axis(mask, order, axis=1)
        before = np.maximum.accumulate(np.where(sm, st, -np.inf), axis=1)
        after = np.minimum.accumulate(np.where(sm, st, np.inf)[:, ::-1], axis=1)[:, ::-1]
        inf = np.full((st.shape[0], 1), np.inf)
        prev = np.concatenate([-inf, before[:, :-1]], axis=1)
        nxt = np.concatenate([after[:, 1:], inf], axis=1)
        with np.errstate(invalid="ignore"):
            near = ((st - prev) < packet_s) | ((nxt - st) < packet_s)
        hit = np.empty_like(near)
        np.put_along_axis(hit, order, near, axis=1)
        out.append(hit & arrivals)
    return out[0], out[1]
