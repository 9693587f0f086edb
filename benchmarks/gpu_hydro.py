"""The GPU-ready hydrodynamics (``docs/gpu.md``): its error against the plugin and its throughput.

Two parts, each printed with the machine's load:

1. **Error against the CPU model**: the same swim flown with the plugin ``bauv.hydro`` (the
   reference) and with the native formulation (:mod:`bauv_sim.hydro_native`), from the same start
   at the missions' 4 ms step: straight at the cruise tail-beat frequency for a third of the
   time, then a 10 deg tail bias (a turn, which exercises sway, yaw and the lagged added mass).
   Reported: the largest horizontal distance between the two tracks, the depth and heading
   differences at the end, and the plugin's own distance flown (the scale of the error).
2. **Vehicles x real time**: ``n`` independent vehicles of the native model stepped for
   ``seconds`` each; simulated vehicle-seconds per wall second, against the plugin model's in the
   same interleaved run (``harness.measure``). On the CPU both are serial ``mj_step`` loops; the
   native one pays a Python passive callback per step, which is what a GPU kernel replaces.

On a machine with MuJoCo Warp and a CUDA device (``--device gpu``) part 2 is where the Warp port
of :func:`bauv_sim.hydro_native.vehicle_force` runs, ``nworld = n`` (``docs/gpu.md``, "Running on
MuJoCo Warp"); that port is not written yet and the script says so (exit status 2). Without
``--device gpu`` it runs both parts on the CPU: ``--smoke`` (CI) in well under a minute.

Usage (from the repository root)::

    python benchmarks/gpu_hydro.py --smoke          # CPU smoke test, CI
    python benchmarks/gpu_hydro.py                  # CPU: 60 s swim, 8 vehicles x 10 s
"""

from __future__ import annotations

import argparse
import copy
import math
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from harness import machine, measure, table

from bauv_sim import build, hydro_native, manoeuvres
from bauv_sim.seabed import SeabedConfig

TIMESTEP_S = 0.004
"""The missions' preset, s."""

CRUISE_FREQUENCY_HZ = 1.2
"""Tail-beat frequency of the swim, Hz (near the 1 m/s cruise of ``models/bauv/speed_table.csv``;
the comparison needs the same input for both, not the exact cruise)."""


def swim(kind: str, seconds: float) -> np.ndarray:
    """Fly the comparison swim with one formulation.

    Args:
        kind: ``"plugin"`` or ``"native"``.
        seconds: simulated time, s (a third straight, the rest with a 10 deg tail bias).

    Returns:
        Per control tick: east, north, up (m, world) and heading (rad), shape (n, 4).
    """
    with hydro_native.formulation(kind):
        p = manoeuvres.open_water_scene(speed_m_s=1.0)
    p.set_timestep(TIMESTEP_S)
    p.set_tail_beat_frequency_hz(CRUISE_FREQUENCY_HZ)
    tick = p.control_tick_s
    n = round(seconds / tick)
    out = np.zeros((n, 4))
    for k in range(n):
        if k == n // 3:
            p.set_tail_bias_rad(math.radians(10.0))
        p.advance(tick)
        out[k, :3] = p.position_world()
        out[k, 3] = p.roll_pitch_heading()[2]
    return out


def error_against_plugin(seconds: float) -> dict[str, float]:
    """Part 1: the native formulation's track against the plugin's (see the module docstring)."""
    ref, nat = swim("plugin", seconds), swim("native", seconds)
    if not (np.all(np.isfinite(ref)) and np.all(np.isfinite(nat))):
        raise SystemExit("gpu_hydro: a swim left finite numbers (NaN or inf in the track)")
    horiz = np.hypot(*(nat[:, :2] - ref[:, :2]).T)
    dheading = (nat[-1, 3] - ref[-1, 3] + math.pi) % (2 * math.pi) - math.pi
    flown = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    return {
        "seconds": seconds,
        "max_horizontal_error_m": float(horiz.max()),
        "final_depth_error_m": float(abs(nat[-1, 2] - ref[-1, 2])),
        "final_heading_error_deg": abs(math.degrees(dheading)),
        "distance_flown_m": flown,
    }


def throughput(n_vehicles: int, seconds: float, repeats: int) -> str:
    """Part 2 on the CPU: vehicle-seconds per wall second, native and plugin, interleaved."""
    variants = {}
    for kind in ("plugin", "native"):
        with hydro_native.formulation(kind):
            p = manoeuvres.open_water_scene(speed_m_s=1.0)
        p.set_timestep(TIMESTEP_S)
        p.set_tail_beat_frequency_hz(CRUISE_FREQUENCY_HZ)
        m = p.model.ptr
        datas = [copy.copy(p.data.ptr) for _ in range(n_vehicles)]
        nstep = round(seconds / TIMESTEP_S)

        def run(m=m, datas=datas, nstep=nstep) -> None:
            for d in datas:
                mujoco.mj_step(m, d, nstep)
            if not all(np.isfinite(d.qpos).all() for d in datas):
                raise SystemExit("gpu_hydro: a vehicle's state is not finite")

        variants[kind] = (run, p)  # keep the physics (and its model) alive
    res = measure(
        {k: v[0] for k, v in variants.items()},
        repeats=repeats,
        warmup=1,
        per={k: n_vehicles * seconds for k in variants},
    )
    lines = [table(res, reference="plugin", unit="wall s per vehicle-second")]
    for k, r in res.items():
        lines.append(
            f"{k}: {1.0 / r.min:.1f} vehicles x real time (best), {1.0 / r.median:.1f} (median)"
        )
    return "\n".join(lines)


def export(folder: Path, seconds: float) -> None:
    """Write what the MuJoCo Warp run needs (``gpu_hydro_warp.py FOLDER``, in an environment
    without bauv_sim): the scene (``scene.xml`` and assets, with the plugin element, which the run
    strips), and ``native.npz``: the native parameters (armature, ``geom_fluid``), the kernel's
    tables, the start state with the tail beating at the cruise frequency and a 10 deg bias, and
    the hull's track each second flown on the CPU with the plugin and with the native callback.

    Args:
        folder: output folder (created).
        seconds: length of the CPU tracks, s.
    """
    import gpu_hydro_warp  # needs warp-lang

    bed = SeabedConfig(
        depth_at_origin_m=200.0, slope=0.0, relief_std_m=0.0, min_depth_m=200.0,
        half_extent_m=2000.0, cell_m=500.0,
    )  # fmt: skip
    cfg = build.SceneConfig(
        vehicles=(build.VehicleSpec(depth_m=20.0, speed_m_s=1.0),), seabed=bed, beacons=()
    )
    folder.mkdir(parents=True, exist_ok=True)
    build.export_scene(cfg, folder)
    out: dict[str, np.ndarray] = {}
    for kind in ("plugin", "native"):
        p = build.build_physics(cfg, timestep_s=TIMESTEP_S, hydrodynamics=kind)
        p.set_tail_beat_frequency_hz(CRUISE_FREQUENCY_HZ)
        p.set_tail_bias_rad(math.radians(10.0))
        m, d = p.model.ptr, p.data.ptr
        if kind == "native":
            v = hydro_native.native_of(m).vehicles[0]
            for k, x in gpu_hydro_warp.table_arrays(m, v).items():
                out["t_" + k] = np.asarray(x)
            out |= {
                "dof_armature": np.array(m.dof_armature),
                "geom_fluid": np.array(m.geom_fluid),
                "timestep": np.array(TIMESTEP_S),
                "wind": np.array(m.opt.wind),
            }
            for name in ("qpos", "qvel", "act", "ctrl", "userdata"):
                out[name] = np.array(getattr(d, name))
        fb = int(m.jnt_bodyid[np.flatnonzero(m.jnt_type == mujoco.mjtJoint.mjJNT_FREE)[0]])
        track = np.zeros((int(seconds), 3))
        for k in range(int(seconds)):
            mujoco.mj_step(m, d, round(1.0 / TIMESTEP_S))
            track[k] = d.xpos[fb]
        out[f"{kind}_track"] = track
    np.savez(folder / "native.npz", **out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--smoke", action="store_true", help="CPU smoke test (CI): short and small")
    ap.add_argument("--device", choices=("cpu", "gpu"), default="cpu")
    ap.add_argument("--vehicles", type=int, default=None, help="vehicles (default 8; smoke 2)")
    ap.add_argument("--seconds", type=float, default=None, help="swim, s (default 60; smoke 9)")
    ap.add_argument("--export", type=Path, help="write the MuJoCo Warp run's input here and stop")
    a = ap.parse_args(argv)
    n = a.vehicles if a.vehicles is not None else (2 if a.smoke else 8)
    seconds = a.seconds if a.seconds is not None else (9.0 if a.smoke else 60.0)
    if n < 1 or not (seconds > 0 and math.isfinite(seconds)):
        print(f"gpu_hydro: vehicles = {n}, seconds = {seconds}: need >= 1 and > 0", file=sys.stderr)
        return 2
    if a.export is not None:
        export(a.export, seconds)
        print(f"wrote {a.export}; run: python benchmarks/gpu_hydro_warp.py {a.export}")
        return 0
    if a.device == "gpu":
        print(
            "gpu_hydro: the GPU run is two steps (docs/gpu.md, 'Running on MuJoCo Warp'): "
            "gpu_hydro.py --export DIR here, then gpu_hydro_warp.py DIR where MuJoCo Warp is",
            file=sys.stderr,
        )
        return 2
    print(machine())
    t0 = time.perf_counter()
    err = error_against_plugin(seconds)
    print("error of the native formulation against the plugin (CPU):")
    for k, v in err.items():
        print(f"  {k}: {v:.4g}")
    print(throughput(n, 2.0 if a.smoke else 10.0, 2 if a.smoke else 5))
    print(f"wall time {time.perf_counter() - t0:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
