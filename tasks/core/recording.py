"""Rerun recordings: one world frame, one ``sim_time`` timeline, series logged in columns.

Sizes of points, lines and arrows are in the viewer's UI points (rerun reads a negative radius
as UI points), so tracks, fixes and way-points stay readable whether the view shows a whole
mission hundreds of metres across or follows a 2 m vehicle.

Per-sample ``log`` calls cost 70-100 us each in rerun 0.41; everything here sends whole columns
(``send_columns``) and logs a finished track once as a static line strip.

Colours are the figures' (:func:`tasks.core.style.rgb`): one table serves matplotlib and rerun.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from bauv_sim.frames import quat_wxyz_from_R, quat_wxyz_to_xyzw
from tasks.core import style
from tasks.core.files import atomic_write_bytes
from tasks.core.lazy import LazyModule

rr = LazyModule("rerun")  # imported when a recording is written or read, not before
rrb = LazyModule("rerun.blueprint", after=(rr,))

TIMELINE = "sim_time"
UI_LINE = -1.5
"""Width of a track's line strip, UI points."""

Color = tuple[int, int, int]


class _DeclaredColours(Mapping[str, Color]):
    """The colours of the declared methods (:data:`tasks.core.style.METHODS`) by method name in
    any case (``COLORS["dr"]`` is the colour of the method declared as DR), as 0-255 RGB: the colour
    the figures draw, so a method looks the same in the PNGs and in rerun; grey for a method no
    imported package declared, as in the figures. Kept for the callers of the former colour
    table of this module; new code calls :func:`tasks.core.style.rgb`."""

    def _name(self, key: str) -> str:
        if key in style.METHODS:
            return key
        for name in style.METHODS:
            if name.lower() == str(key).lower():
                return name
        return key

    def __getitem__(self, key: str) -> Color:
        return style.rgb(self._name(key))

    def __contains__(self, key: object) -> bool:
        return isinstance(key, str) and self._name(key) in style.METHODS

    def __iter__(self) -> Iterator[str]:
        return iter(style.METHODS)

    def __len__(self) -> int:
        return len(style.METHODS)


COLORS: Mapping[str, Color] = _DeclaredColours()
"""Method -> its declared colour as 0-255 RGB (:func:`tasks.core.style.rgb`), any case."""


class Recording:
    """A rerun recording written to a file.

    The recording is encoded into memory as it is logged and written when it is closed, atomically
    (:func:`tasks.core.files.atomic_write_bytes`): a recording is whole or absent (never the
    truncated file a full disk leaves when rerun writes it as it goes), a full disk raises a plain
    :class:`OSError`, and a run folder's recording is never written through a symbolic link.

    Args:
        path: the ``.rrd`` file to write (on :meth:`close`).
        app_id: rerun application id (e.g. the experiment name).
        recording_id: a stable id (e.g. ``"<experiment>/seed<s>/run<i>"``), so that the same run
            gives the same recording id.
    """

    def __init__(self, path: Path, app_id: str, recording_id: str):
        self.path = Path(path)
        # rerun application ids are entry names: no "/"
        self.rec = rr.RecordingStream(app_id.replace("/", "-"), recording_id=recording_id)
        self._stream = self.rec.binary_stream()
        # the world frame is declared once: x east, y north, z up
        self.rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)

    def _time(self, t_s: NDArray[np.float64]) -> list[rr.TimeColumn]:
        return [rr.TimeColumn(TIMELINE, duration=np.asarray(t_s, dtype=float))]

    def track(
        self,
        entity: str,
        t_s: NDArray[np.float64],
        pos_world_m: NDArray[np.float64],
        color: Color,
        radius_m: float = -5.0,
        strip: bool = True,
        label: str | None = None,
    ) -> None:
        """A moving point over time (one row per time) and, if ``strip``, its whole path once;
        rows with a non-finite position are left out.

        Args:
            entity: entity path under ``world/``.
            t_s: times, shape (T,), s.
            pos_world_m: positions, shape (T, 3), m, world.
            radius_m: the moving point's radius, m (negative: UI points).
            label: the moving point's label in the 3-D view (e.g. ``"f1 GA1"``), or None.
        """
        pos = np.asarray(pos_world_m, dtype=float)
        keep = np.isfinite(pos).all(axis=1)  # an estimate not yet started (NaN) is left out
        pos, t_s = pos[keep], np.asarray(t_s, dtype=float)[keep]
        self.rec.send_columns(
            f"world/{entity}/position",
            indexes=self._time(t_s),
            columns=rr.Points3D.columns(positions=pos),
        )
        self.rec.log(
            f"world/{entity}/position",
            rr.Points3D.from_fields(
                radii=radius_m, colors=color, labels=None if label is None else [label]
            ),
            static=True,
        )
        if strip:
            self.rec.log(
                f"world/{entity}/path",
                rr.LineStrips3D([pos], colors=color, radii=UI_LINE),
                static=True,
            )

    def fixes(
        self,
        entity: str,
        t_s: NDArray[np.float64],
        pos_world_m: NDArray[np.float64],
        color: Color,
    ) -> None:
        """Discrete position fixes (USBL, GPS): a point at each fix time and all fixes at once."""
        pos = np.asarray(pos_world_m, dtype=float)
        if len(pos) == 0:
            return
        self.rec.send_columns(
            f"world/{entity}/latest",
            indexes=self._time(t_s),
            columns=rr.Points3D.columns(positions=pos),
        )
        self.rec.log(
            f"world/{entity}/latest", rr.Points3D.from_fields(radii=-6.0, colors=color), static=True
        )
        self.rec.log(f"world/{entity}/all", rr.Points3D(pos, radii=-2.5, colors=color), static=True)

    def ellipsoids(
        self,
        entity: str,
        t_s: NDArray[np.float64],
        centers_world_m: NDArray[np.float64],
        cov_world_m2: NDArray[np.float64],
        color: Color,
        k_sigma: float = 1.0,
    ) -> None:
        """Covariance ellipsoids over time: half sizes ``k_sigma * sqrt(eigenvalues)`` along the
        eigenvectors; rows with a non-finite centre or covariance are left out.

        Args:
            centers_world_m: shape (T, 3).
            cov_world_m2: shape (T, 3, 3).
        """
        centers = np.asarray(centers_world_m, dtype=float)
        cov = np.asarray(cov_world_m2, dtype=float)
        keep = np.isfinite(centers).all(axis=1) & np.isfinite(cov).all(axis=(1, 2))
        centers, cov, t_s = centers[keep], cov[keep], np.asarray(t_s, dtype=float)[keep]
        half, quat_xyzw = covariance_ellipsoids(cov, k_sigma)
        self.rec.send_columns(
            f"world/{entity}/covariance",
            indexes=self._time(t_s),
            columns=rr.Ellipsoids3D.columns(
                centers=centers,
                half_sizes=half,
                quaternions=quat_xyzw,
            ),
        )
        self.rec.log(
            f"world/{entity}/covariance",
            rr.Ellipsoids3D.from_fields(
                colors=color, fill_mode=rr.components.FillMode.MajorWireframe
            ),
            static=True,
        )

    def arrows(
        self,
        entity: str,
        t_s: NDArray[np.float64],
        origins_world_m: NDArray[np.float64],
        vectors_world: NDArray[np.float64],
        color: Color,
    ) -> None:
        """Arrows over time (one per row), e.g. the current at the vehicle, scaled by the caller.

        Args:
            entity: entity path under ``world/``.
            t_s: times, shape (T,), s.
            origins_world_m: arrow tails, shape (T, 3), m, world.
            vectors_world: arrows, shape (T, 3) (or (T, 2) horizontal), world.
        """
        v = np.asarray(vectors_world, dtype=float)
        if v.shape[-1] == 2:
            v = np.column_stack([v, np.zeros(len(v))])
        self.rec.send_columns(
            f"world/{entity}",
            indexes=self._time(t_s),
            columns=rr.Arrows3D.columns(origins=np.asarray(origins_world_m, float), vectors=v),
        )
        self.rec.log(
            f"world/{entity}", rr.Arrows3D.from_fields(colors=color, radii=-2.0), static=True
        )

    def scalars(
        self,
        entity: str,
        t_s: NDArray[np.float64],
        values: NDArray[np.float64],
        color: Color | None = None,
        name: str | None = None,
    ) -> None:
        """A time series (a plot line), e.g. ``distance/ekf``; NaN samples are left out."""
        if color is not None or name is not None:
            self.rec.log(
                entity,
                rr.SeriesLines(
                    colors=None if color is None else [color],
                    names=None if name is None else [name],
                ),
                static=True,
            )
        v = np.asarray(values, dtype=float)
        keep = np.isfinite(v)
        self.rec.send_columns(
            entity,
            indexes=self._time(np.asarray(t_s)[keep]),
            columns=rr.Scalars.columns(scalars=v[keep]),
        )

    def point(
        self, entity: str, pos_world_m: NDArray[np.float64], color: Color, label: str
    ) -> None:
        """A static landmark (transceiver, beacon, way-point)."""
        self.rec.log(
            f"world/{entity}",
            rr.Points3D([pos_world_m], radii=-8.0, colors=color, labels=[label]),
            static=True,
        )

    def events(self, entity: str, t_s, texts, levels) -> None:
        """A text log of events (way-point reached, surfacing, gate rejections), one row each.

        Args:
            entity: entity path, e.g. ``"events"``.
            t_s: event times, shape (k,), s.
            texts: the events in words, k strings.
            levels: rerun log levels (``"INFO"``, ``"WARN"``...), k strings.
        """
        if len(texts) == 0:
            return
        order = np.argsort(np.asarray(t_s, dtype=float), kind="stable")
        self.rec.send_columns(
            entity,
            indexes=self._time(np.asarray(t_s, dtype=float)[order]),
            columns=rr.TextLog.columns(
                text=[texts[i] for i in order], level=[levels[i] for i in order]
            ),
        )

    def blueprint(
        self,
        *plots: str,
        follow: str | None = None,
        log: str | None = None,
        world_name: str = "world",
        eye_controls: rrb.EyeControls3D | None = None,
    ) -> None:
        """Open on the 3-D world beside one time-series view per plot root.

        Args:
            plots: entity roots, one time-series view each.
            follow: an entity the 3-D camera rides with (e.g. ``"/world/vehicle"``): the view's
                space is that entity's frame, so the vehicle stays in view at mission scale;
                ``None``: the world frame.
            log: a text-log entity shown under the 3-D view (the events).
            world_name: the 3-D view's title.
            eye_controls: the 3-D camera's first pose (in the view's space: the followed
                entity's frame when ``follow`` is given), e.g. ``rrb.EyeControls3D(position=...,
                look_target=...)``.
        """
        views = [rrb.TimeSeriesView(origin=p, name=p) for p in plots]
        if follow:
            # the view's space is the followed entity's frame: the camera rides with the vehicle
            # (the whole world is drawn, transformed into that frame)
            world = rrb.Spatial3DView(
                origin=follow, contents="/world/**", name=world_name, eye_controls=eye_controls
            )
        else:
            world = rrb.Spatial3DView(origin="world", name=world_name, eye_controls=eye_controls)
        left = (
            rrb.Vertical(world, rrb.TextLogView(origin=log, name=log), row_shares=[4, 1])
            if log
            else world
        )
        self.rec.send_blueprint(
            rrb.Blueprint(
                rrb.Horizontal(
                    left,
                    rrb.Vertical(*views) if views else rrb.Spatial3DView(origin="world"),
                    column_shares=[3, 2],
                ),
                collapse_panels=True,
            )
        )

    def close(self) -> None:
        """Flush the recording and write its file.

        Raises:
            OSError: if the file cannot be written (nothing is left at its name).
        """
        self.rec.flush()
        data = self._stream.read(flush=True) or b""
        self.rec.disconnect()  # the stream's end
        data += self._stream.read(flush=False) or b""
        atomic_write_bytes(self.path, data)


def covariance_ellipsoids(
    cov: NDArray[np.float64], k_sigma: float = 1.0
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Half sizes and rotations of covariance ellipsoids.

    Args:
        cov: covariances, shape (..., 3, 3).
        k_sigma: scale in standard deviations.

    Returns:
        ``(half_sizes (..., 3), quat_xyzw (..., 4))``: the rotation maps the ellipsoid's axes to
        the eigenvectors (columns made right-handed).
    """
    w, V = np.linalg.eigh(np.asarray(cov, dtype=float))
    det = np.linalg.det(V)
    V[..., :, 2] *= np.sign(det)[..., None]
    half = k_sigma * np.sqrt(np.maximum(w, 0.0))
    return half, quat_wxyz_to_xyzw(quat_wxyz_from_R(V))


def entity_paths(path: Path) -> set[str]:
    """The entity paths of an ``.rrd`` file (static and temporal), e.g. ``"/world/bauv/body"``."""
    import rerun.chunk as rc

    return {chunk.entity_path for chunk in rc.RrdReader(str(path)).stream().to_chunks()}


def read_static(path: Path, entity: str, component: str) -> list:
    """Read one static component of one entity back from an ``.rrd`` file: its rows' values
    (e.g. ``("world/bauv/ekf/position", "Points3D:labels")`` -> ``[["bauv EKF"]]``)."""
    import rerun.chunk as rc

    want = "/" + entity.strip("/")
    out: list = []
    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path != want or not chunk.is_static:
            continue
        rb = chunk.to_record_batch()
        if component in rb.schema.names:
            out += rb.column(component).to_pylist()
    return out


def read_text_log(path: Path, entity: str) -> list[tuple[float, str, str]]:
    """Read a text log back from an ``.rrd`` file: ``[(t_s, level, text), ...]`` by time."""
    import rerun.chunk as rc

    want = "/" + entity.strip("/")
    rows = []
    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path != want or chunk.is_static:
            continue
        rb = chunk.to_record_batch()
        names = rb.schema.names
        tcol = next((n for n in names if n.endswith("TextLog:text")), None)
        lcol = next((n for n in names if n.endswith("TextLog:level")), None)
        if tcol is None or TIMELINE not in names:
            continue
        t = rb.column(TIMELINE).cast("int64").to_numpy() * 1e-9
        texts = rb.column(tcol).to_pylist()
        levels = rb.column(lcol).to_pylist() if lcol else [[""]] * len(texts)
        for ti, tx, lv in zip(t, texts, levels, strict=True):
            rows.append((float(ti), (lv or [""])[0], (tx or [""])[0]))
    return sorted(rows, key=lambda r: r[0])


def read_time_series(
    path: Path, entity: str, component: str
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Read one temporal component of one entity back from an ``.rrd`` file.

    Args:
        path: the recording.
        entity: entity path, e.g. ``"world/ekf/position"``.
        component: column name, e.g. ``"Points3D:positions"`` or ``"Scalars:scalars"``.

    Returns:
        ``(t_s (k,), values (k, ...))`` sorted by ``sim_time``; each row's first instance.
    """
    import rerun.chunk as rc

    want = "/" + entity.strip("/")
    times, rows = [], []
    for chunk in rc.RrdReader(str(path)).stream().to_chunks():
        if chunk.entity_path != want or chunk.is_static:
            continue
        rb = chunk.to_record_batch()
        if component not in rb.schema.names or TIMELINE not in rb.schema.names:
            continue
        t = rb.column(TIMELINE).cast("int64").to_numpy() * 1e-9
        vals = rb.column(component).to_pylist()
        times.append(t)
        rows += [np.asarray(v[0] if isinstance(v, list) else v, dtype=float) for v in vals]
    if not times:
        raise KeyError(f"{entity}:{component} not in {path}")
    t = np.concatenate(times)
    order = np.argsort(t, kind="stable")
    return t[order], np.asarray(rows)[order]
