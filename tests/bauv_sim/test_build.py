"""Scene assembly: the built default scene equals the scene file; names are namespaced; sites sit
on the seabed that MuJoCo collides with."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from bauv_sim import build, seabed
from bauv_sim.config import validate
from bauv_sim.errors import ConfigError, GeometryError
from bauv_sim.hull import MODEL_DIR


def _ids(m: mujoco.MjModel, kind: mujoco.mjtObj, n: int) -> list[str]:
    return [mujoco.mj_id2name(m, kind, i) for i in range(n)]


def test_default_build_matches_the_scene_file():
    plain = mujoco.MjModel.from_xml_path(str(MODEL_DIR / "scene.xml"))
    built = build.build_physics().model.ptr
    for name in ["usbl_transceiver", "beacon_0", "beacon_1", "beacon_2", "beacon_3"]:
        a = plain.site(name).pos
        b = built.site(name).pos
        assert np.allclose(a, b, atol=1e-4), name
    assert np.allclose(plain.hfield_size, built.hfield_size, atol=1e-4)
    assert np.array_equal(plain.hfield_data, built.hfield_data)
    assert np.allclose(plain.geom("seabed").pos, built.geom("seabed").pos, atol=1e-4)
    # the same vehicle: body masses and fluid parameters, names with the vehicle's prefix
    # the built scene has one more body: the massless attachment frame that carries the free joint
    assert built.nbody == plain.nbody + 1 and plain.nv == built.nv and plain.nu == built.nu
    assert np.allclose(
        np.sort(plain.body_mass[plain.body_mass > 0]), np.sort(built.body_mass[built.body_mass > 0])
    )
    # (the plain load keeps its virtual masses, columns 6-11; the facade removes them)
    assert np.allclose(
        np.sort(plain.geom_fluid[:, :6], axis=0), np.sort(built.geom_fluid[:, :6], axis=0)
    )
    assert "bauv/hull" in _ids(built, mujoco.mjtObj.mjOBJ_BODY, built.nbody)


def test_two_vehicles_are_namespaced_and_placed():
    cfg = build.SceneConfig(
        vehicles=(
            build.VehicleSpec(name="leader", east_m=5.0, heading_deg=45.0, speed_m_s=1.0),
            build.VehicleSpec(name="follower", east_m=-15.0, north_m=2.0, depth_m=4.0),
        )
    )
    phys = build.build_physics(cfg)
    m = phys.model.ptr
    assert phys.vehicle_names() == ["leader", "follower"]
    for kind, n in [
        (mujoco.mjtObj.mjOBJ_SITE, m.nsite),
        (mujoco.mjtObj.mjOBJ_ACTUATOR, m.nu),
        (mujoco.mjtObj.mjOBJ_JOINT, m.njnt),
        (mujoco.mjtObj.mjOBJ_GEOM, m.ngeom),
    ]:
        names = _ids(m, kind, n)
        assert len(set(names)) == len(names) and all(names)
    assert "follower/usbl_transponder" in _ids(m, mujoco.mjtObj.mjOBJ_SITE, m.nsite)
    assert np.allclose(phys.position_world("follower"), [-15.0, 2.0, -4.0])
    assert phys.heading_rad("leader") == pytest.approx(np.radians(45.0))
    assert np.allclose(phys.velocity_world("leader"), [np.sqrt(0.5), np.sqrt(0.5), 0.0])
    # each vehicle is actuated on its own
    phys.set_tail_beat_frequency_hz(1.5, vehicle="follower")
    phys.advance(1.0)
    assert phys.tail_beat_frequency_hz("follower") == pytest.approx(1.5, rel=0.05)
    assert phys.tail_beat_frequency_hz("leader") == pytest.approx(0.0, abs=1e-6)


def test_bad_scenes_are_refused():
    with pytest.raises(ConfigError, match="distinct"):
        validate(build.SceneConfig, {"vehicles": [{"name": "a"}, {"name": "a"}]})
    with pytest.raises(ConfigError, match="name"):
        validate(build.SceneConfig, {"vehicles": [{"name": "a/b"}]})
    with pytest.raises(GeometryError, match="seabed"):
        build.build_scene(build.SceneConfig(vehicles=(build.VehicleSpec(depth_m=5.9),)))


def test_seabed_heights_are_the_surface_mujoco_collides_with():
    phys = build.build_physics(build.SceneConfig(vehicles=(build.VehicleSpec(depth_m=1.0),)))
    bed = seabed.generate()
    m, d = phys.model.ptr, phys.data.ptr
    rng = np.random.default_rng(4)
    geomid = np.array([-1], dtype=np.int32)
    for x, y in rng.uniform(-900, 900, size=(20, 2)):
        dist = mujoco.mj_ray(
            m, d, np.array([x, y, 5.0]), np.array([0, 0, -1.0]), None, 1, -1, geomid
        )
        assert 5.0 - dist == pytest.approx(float(bed.height_world(x, y)), abs=1e-4)
    # the transceiver lies on the seabed at 6 m depth, beacons 1 m above it
    assert np.allclose(m.site("usbl_transceiver").pos, [0, 0, -6.0], atol=1e-6)
    for i, (e, n) in enumerate([(300, 300), (-300, 300), (-300, -300), (300, -300)]):
        assert m.site(f"beacon_{i}").pos[2] == pytest.approx(float(bed.height_world(e, n)) + 1.0)


def test_a_custom_seabed_replaces_the_heightfield():
    cfg = build.SceneConfig(
        seabed=seabed.SeabedConfig(
            depth_at_origin_m=30.0,
            relief_std_m=0.0,
            slope=0.0,
            min_depth_m=30.0,
            half_extent_m=500.0,
            cell_m=50.0,
        ),
        transceiver_east_m=100.0,
        beacons=(),
    )
    phys = build.build_physics(cfg)
    m = phys.model.ptr
    assert m.hfield_nrow[0] == 21 and m.nsite == 1 + 13  # transceiver + the vehicle's 13 sites
    assert np.allclose(m.site("usbl_transceiver").pos, [100.0, 0.0, -30.0], atol=1e-6)


def test_seabed_generator_laws():
    bed = seabed.generate()
    c = bed.config
    assert float(bed.depth_at(0.0, 0.0)) == pytest.approx(c.depth_at_origin_m, abs=1e-5)
    assert bed.depth_m.min() >= c.min_depth_m - 1e-12
    # relief statistics over the grid: standard deviation near the configured one
    flat = seabed.generate(c.model_copy(update={"relief_std_m": 0.0}))
    relief = bed.depth_m - flat.depth_m
    assert 0.5 * c.relief_std_m < np.std(relief) < 1.5 * c.relief_std_m
    # same seed, same seabed; another seed, another one
    assert np.array_equal(seabed.generate().depth_m, bed.depth_m)
    assert not np.array_equal(
        seabed.generate(c.model_copy(update={"seed": 2})).depth_m, bed.depth_m
    )
    assert seabed.DEFAULT_SEABED_FILE.read_bytes() == bed.to_bytes()
    with pytest.raises(GeometryError):
        bed.height_world(2000.0, 0.0)
