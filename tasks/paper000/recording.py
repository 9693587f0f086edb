"""The recording of one seed 000 passage (``recording.rrd``, rerun)."""

from __future__ import annotations

import numpy as np

from tasks.core.recording import COLORS, Recording
from tasks.core.registry import Experiment
from tasks.paper000.run import simulate_passages
from tasks.paper000.scenario import Paper000Scenario


def record_passage(exp: Experiment, scn: Paper000Scenario, seed: int, run: int, out_dir) -> str:
    """Write ``recording.rrd`` for one passage (re-simulated: identical to its batch numbers).

    The recording holds the reference, DR and EKF tracks (the EKF's covariance ellipsoids), the
    USBL fixes split into those the filter applied and those its gate rejected, the distances,
    the EKF's NEES against the chi-square band of one run and the NIS of each fix, an event log
    (fixes rejected, fixes not produced, the closest approach) and a 3-D view that rides with
    the vehicle (the hull drawn on the reference, heading along the course).
    """
    import rerun as rr
    import rerun.blueprint as rrb

    from bauv_sim.frames import R_from_roll_pitch_heading, quat_wxyz_from_R, quat_wxyz_to_xyzw
    from bauv_sim.hull import MODEL_DIR

    p = simulate_passages(scn, seed, (run,))
    t = p.truth.t_s
    rec = Recording(out_dir / "recording.rrd", exp.name, f"{exp.name}/seed{seed}/run{run}")
    tx = scn.transceiver.position_world_m()
    rec.point("transceiver", tx, (0, 0, 0), "USBL transceiver")
    rec.track("truth", t, p.reference_m, COLORS["truth"])
    rec.track("dr", t, p.dr_m[0], COLORS["dr"])
    rec.track("ekf", t, p.ekf_m[0], COLORS["ekf"])
    rec.ellipsoids("ekf", t, p.ekf_m[0], p.ekf_P[0], COLORS["ekf"])
    heading = np.broadcast_to(p.truth.heading_rad, (1, len(t)))[0]
    R = np.stack([R_from_roll_pitch_heading(0.0, 0.0, float(h)) for h in heading])
    rec.rec.send_columns(
        "world/vehicle",
        indexes=[rr.TimeColumn("sim_time", duration=t)],
        columns=rr.Transform3D.columns(
            translation=p.reference_m, quaternion=quat_wxyz_to_xyzw(quat_wxyz_from_R(R))
        ),
    )
    rec.rec.log(
        "world/vehicle/hull", rr.Asset3D(path=MODEL_DIR / "assets" / "hull.obj"), static=True
    )
    ok = p.usbl_produced[0]
    rej = p.gate_rejected[0] & ok
    applied = ok & ~rej
    rec.fixes("usbl/accepted", p.t_fix_s[applied], p.usbl_m[0][applied], COLORS["usbl"])
    rec.fixes("usbl/rejected", p.t_fix_s[rej], p.usbl_m[0][rej], (230, 0, 0))
    rec.scalars(
        "fixes/usbl_accepted",
        p.t_fix_s[ok],
        applied[ok].astype(float),
        COLORS["usbl"],
        "USBL fix applied (1) or rejected by the gate (0)",
    )
    d = p.distances()
    rec.scalars("distance/ekf", t, d["EKF"][0], COLORS["ekf"], "EKF (horizontal, m)")
    rec.scalars("distance/dr", t, d["DR"][0], COLORS["dr"], "DR (horizontal, m)")
    rec.scalars("distance/usbl", p.t_fix_s[ok], d["USBL"][0][ok], COLORS["usbl"], "USBL (3-D, m)")
    rec.scalars("consistency/nees_ekf", t, p.ekf_nees()[0], COLORS["ekf"], "EKF NEES (dof 3)")
    q = scn.report.consistency_probability
    from scipy.stats import chi2  # imported with the recording only

    lo, hi = np.asarray(chi2.ppf(np.array([(1 - q) / 2, (1 + q) / 2]), 3))
    for name, val in (("low", lo), ("high", hi)):
        rec.scalars(
            f"consistency/nees_band_{name}",
            t[[0, -1]],
            np.full(2, val),
            (0, 158, 115),
            f"{100 * q:g} % chi-square band, one run ({val:.2f})",
        )
    nis = p.nis[0]
    rec.scalars("consistency/nis_usbl", p.t_fix_s, nis, COLORS["usbl"], "USBL NIS (dof 3)")
    times, texts, levels = [float(t[0])], ["start of the passage"], ["INFO"]
    for k in range(len(p.t_fix_s)):
        if not ok[k]:
            times.append(float(p.t_fix_s[k]))
            texts.append("no USBL fix (range, field of view or dropout)")
            levels.append("WARN")
        elif rej[k]:
            n = f" (NIS {nis[k]:.1f})" if np.isfinite(nis[k]) else ""
            times.append(float(p.t_fix_s[k]))
            texts.append(f"USBL fix rejected by the gate{n}")
            levels.append("WARN")
    kc = int(np.argmin(np.linalg.norm(p.reference_m[:, :2] - tx[:2], axis=1)))
    times.append(float(t[kc]))
    texts.append("closest approach to the transceiver")
    levels.append("INFO")
    times.append(float(t[-1]))
    texts.append("end of the passage")
    levels.append("INFO")
    rec.events("events", times, texts, levels)
    rec.blueprint(
        "distance",
        "consistency",
        "fixes",
        follow="/world/vehicle",
        eye_controls=rrb.EyeControls3D(
            position=[-60.0, 30.0, 40.0], look_target=[0.0, 0.0, 0.0], eye_up=[0.0, 0.0, 1.0]
        ),
        log="events",
        world_name="world (camera rides with the vehicle)",
    )
    rec.close()
    return "recording.rrd"
