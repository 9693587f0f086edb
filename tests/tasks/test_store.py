"""The plain-data store: every supported value comes back with the same types and the same bits,
every experiment's block result comes back whole, and a crafted file is refused with StoreError
without anything it names being imported or run."""

import collections
import dataclasses
import io
import json
import math
import pathlib
import pickle
import struct
import sys
import zipfile

import numpy as np
import pytest
from pydantic import BaseModel

from tasks.core import registry, store
from tasks.core.runner import plan_batch
from tasks.core.store import StoreError


def same(a, b, path="value"):
    """Deep comparison by type and bits (independent of the codec)."""
    assert type(a) is type(b), f"{path}: {type(a)} != {type(b)}"
    if type(a) is float:
        assert struct.pack(">d", a) == struct.pack(">d", b), f"{path}: {a!r} != {b!r}"
    elif isinstance(a, np.ndarray):
        assert (a.dtype.str, a.shape) == (b.dtype.str, b.shape), path
        f_order = a.ndim > 1 and a.flags.f_contiguous and not a.flags.c_contiguous
        assert f_order == (b.ndim > 1 and b.flags.f_contiguous and not b.flags.c_contiguous), path
        assert a.tobytes(order="A") == b.tobytes(order="A"), path
        assert b.flags.writeable, path
    elif isinstance(a, np.generic):
        assert a.dtype.str == b.dtype.str and a.tobytes() == b.tobytes(), path
    elif type(a) in (list, tuple):
        assert len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            same(x, y, f"{path}[{i}]")
    elif type(a) is dict:
        assert len(a) == len(b), path
        for (ka, va), (kb, vb) in zip(a.items(), b.items(), strict=True):  # order kept
            same(ka, kb, f"{path} key")
            same(va, vb, f"{path}[{ka!r}]")
    elif dataclasses.is_dataclass(a):
        for f in dataclasses.fields(a):
            if f.metadata.get("store", True):
                same(getattr(a, f.name), getattr(b, f.name), f"{path}.{f.name}")
    elif isinstance(a, BaseModel):
        assert a == b, path
    else:
        assert a == b, path


def roundtrip(value, header=None):
    return store.loads(store.dumps(value, header), "test.zip")


def bits(h):
    return struct.unpack(">d", bytes.fromhex(h))[0]


FLOATS = [
    0.0,
    -0.0,
    1.0,
    -1.5,
    0.1,
    1 / 3,
    math.pi,
    1e16,
    123456789012345678.0,
    5e-324,  # smallest subnormal
    -5e-324,
    bits("000fffffffffffff"),  # largest subnormal
    bits("0010000000000000"),  # smallest normal
    bits("7fefffffffffffff"),  # largest finite
    math.inf,
    -math.inf,
    bits("7ff8000000000000"),  # quiet NaN
    bits("fff8000000000000"),  # negative NaN
    bits("7ff8dead0000beef"),  # NaN with a payload
    bits("7ff0000000000001"),  # signalling NaN
]


def test_float_fixtures_are_what_they_say():
    assert struct.pack(">d", FLOATS[-1]).hex() == "7ff0000000000001"
    assert struct.pack(">d", FLOATS[-2]).hex() == "7ff8dead0000beef"
    assert math.copysign(1.0, FLOATS[1]) == -1.0 and FLOATS[9] > 0 and FLOATS[9] / 2 == 0.0


@pytest.mark.parametrize("x", FLOATS, ids=lambda x: struct.pack(">d", x).hex())
def test_python_floats_keep_every_bit(x):
    got = roundtrip([x, (x,), {"k": x}, {x: 1} if not math.isnan(x) else {}]).value
    same(got, [x, (x,), {"k": x}, {x: 1} if not math.isnan(x) else {}])


def test_plain_python_values():
    value = [
        None,
        True,
        False,
        0,
        -7,
        2**200,
        -(2**70),
        "",
        'ünïcødé ✓ "quoted"\n\ttab',
        [],
        (),
        {},
        [1, [2, [3, ()]], (4, [5])],
        ("a", 1, 1.0, None),
    ]
    same(roundtrip(value).value, value)


def test_dicts_keep_key_types_and_order():
    value = {
        "z": 1,
        2: "two",
        1: "one",
        1.5: [1.5],
        -0.0: "negative zero",
        (1, "x", (2.5,)): "tuple key",
        None: "none",
        np.int64(7): "numpy key",
        "a": {"nested": {3: [4]}},
    }
    got = roundtrip(value).value
    same(got, value)
    assert list(got) == list(value)
    assert math.copysign(1.0, next(k for k in got if k == 0.0)) == -1.0
    assert roundtrip({True: 1, 5: 2}).value == {True: 1, 5: 2}
    assert type(next(iter(roundtrip({True: 1}).value))) is bool


DTYPES = [
    "?",
    "i1",
    "i2",
    "i4",
    "i8",
    "u1",
    "u2",
    "u4",
    "u8",
    "f2",
    "f4",
    "f8",
    "g",
    "c8",
    "c16",
    "<U7",
    ">f8",
    ">i4",
    ">c16",
    ">U3",
]


@pytest.mark.parametrize("dtype", DTYPES)
def test_arrays_of_every_dtype(dtype):
    rng = np.random.default_rng(1)
    dt = np.dtype(dtype)
    if dt.kind == "U":
        a = np.array([["ab", "ü✓", ""], ["xyz", "q", "ww"]], dtype=dt)
    elif dt.kind == "b":
        a = rng.random((2, 3)) < 0.5
    elif dt.kind in "iu":
        info = np.iinfo(dt)
        a = np.array([[info.min, info.max, 0], [1, 2, 3]], dtype=dt)
    else:
        a = (rng.normal(size=(2, 3)) * 1e3).astype(dt)
    same(roundtrip(a).value, a)


def test_array_layouts_shapes_and_special_floats():
    base = np.arange(24, dtype=np.float64).reshape(2, 3, 4)
    with np.errstate(over="ignore"):
        f32 = np.array(FLOATS, dtype=np.float32)
    values = [
        np.array(FLOATS),
        f32,
        np.array([complex(x, -x) for x in FLOATS]),
        np.float64(3.5) * np.ones(()),  # 0-d
        np.zeros((0, 3)),
        np.zeros((4, 0), dtype=np.int16),
        np.asfortranarray(base),
        base[:, ::2, 1:],  # not contiguous
        base.transpose(2, 0, 1),
        np.array(["", "x"]),
    ]
    got = roundtrip(values).value
    same(got, [np.ascontiguousarray(v) if not v.flags.f_contiguous else v for v in values])
    assert got[6].flags.f_contiguous and not got[6].flags.c_contiguous


def test_numpy_scalars():
    value = [
        np.float64(-0.0),
        np.float32(bits("7ff8dead0000beef")),
        np.float16(1.5),
        np.longdouble("0.1"),
        np.int8(-5),
        np.uint64(2**64 - 1),
        np.int64(-(2**63)),
        np.bool_(True),
        np.False_,
        np.complex128(1 + 2j),
        np.complex64(-0.0 - 0.0j),
        np.str_("näive ✓"),
        np.str_(""),
    ]
    same(roundtrip(value).value, value)


@store.plain_data("tests.store.Point")
@dataclasses.dataclass(frozen=True)
class Point:
    x: float
    y: float
    tag: str = "p"


@store.plain_data("tests.store.Holder")
@dataclasses.dataclass
class Holder:
    points: list
    arrays: dict
    live: object = dataclasses.field(default=None, repr=False, metadata=store.NOT_STORED)


@store.plain_data("tests.store.Model")
class Model(BaseModel):
    a: int
    b: tuple[float, ...]
    c: dict[str, list[int]]
    d: Point | None = None


def test_registered_dataclasses_and_models():
    live = object()
    value = Holder(
        points=[Point(1.0, -0.0), Point(math.nan, math.inf, "q")],
        arrays={"P": np.eye(3), "k": (Point(0.5, 5e-324),)},
        live=live,
    )
    data = store.dumps(value)
    got = store.loads(data).value
    same(got, value)
    assert got.live is None  # not stored: its default
    assert b"live" not in zipfile.ZipFile(io.BytesIO(data)).read(store.MANIFEST)
    m = Model(a=3, b=(1.0, -0.0, 2.5), c={"x": [1, 2]}, d=Point(1.0, 2.0))
    same(roundtrip({"m": m, "list": [m]}).value, {"m": m, "list": [m]})


def test_the_same_value_always_gives_the_same_bytes():
    v = {"a": np.arange(5.0), "b": [Point(1.0, 2.0)], "c": (1, "x")}
    assert store.dumps(v, {"seed": 1}) == store.dumps(dict(v), {"seed": 1})


def test_header_round_trips():
    got = roundtrip(None, {"experiment": "x", "runs": [1, 2], "seed": 0})
    assert got.header == {"experiment": "x", "runs": [1, 2], "seed": 0} and got.value is None


# ---------------------------------------------------------------------------------------------
# what is not plain data


@dataclasses.dataclass
class Unregistered:
    x: int = 1


class Plain:
    pass


@pytest.mark.parametrize(
    ("value", "where"),
    [
        ({"x": [np.array([1, "a"], dtype=object)]}, "value['x'][0]"),
        (np.ma.array([1.0, 2.0]), "ndarray subclass"),
        (np.array(["2020-01-01"], dtype="datetime64[D]"), "datetime64"),
        (np.zeros(2, dtype=[("a", "f8")]), "not plain data"),
        (np.datetime64("2020-01-01"), "numpy scalar"),
        ({1, 2}, "builtins.set"),
        (b"bytes", "builtins.bytes"),
        (collections.defaultdict(list), "defaultdict"),
        (collections.OrderedDict(a=1), "OrderedDict"),
        ([Unregistered()], "Unregistered"),
        (Plain(), "Plain"),
        (Holder([Plain()], {}), "value.points[0]"),
        (lambda: 0, "function"),
        (1 + 2j, "complex"),
    ],
)
def test_what_is_not_plain_data_is_refused_with_its_path(value, where):
    with pytest.raises(StoreError) as exc:
        store.dumps(value)
    assert where in str(exc.value) and "\n" not in str(exc.value)


def test_a_value_that_contains_itself_is_refused():
    loop: list = []
    loop.append(loop)
    with pytest.raises(StoreError, match="contains itself"):
        store.dumps(loop)


def test_registration_rules():
    with pytest.raises(TypeError, match="not a dataclass"):
        store.plain_data("tests.store.Plain")(Plain)

    @dataclasses.dataclass
    class NoDefault:
        task: object = dataclasses.field(metadata=store.NOT_STORED)

    with pytest.raises(TypeError, match="needs a default"):
        store.plain_data("tests.store.NoDefault")(NoDefault)

    @dataclasses.dataclass
    class Other:
        x: int

    with pytest.raises(ValueError, match="is taken by"):
        store.plain_data("tests.store.Point")(Other)
    with pytest.raises(ValueError, match="already registered"):
        store.plain_data("tests.store.Point2")(Point)
    with pytest.raises(ValueError, match="must match"):
        store.plain_data("bad name")
    assert store.registered()["tests.store.Point"] is Point


# ---------------------------------------------------------------------------------------------
# crafted, damaged and foreign files


def craft(manifest, members=None, compress=zipfile.ZIP_STORED):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compress) as zf:
        zf.writestr(
            store.MANIFEST, manifest if isinstance(manifest, bytes) else json.dumps(manifest)
        )
        for name, data in (members or {}).items():
            zf.writestr(name, data)
    return buf.getvalue()


def manifest(value, arrays=(), **over):
    return {
        "format": store.FORMAT,
        "version": store.VERSION,
        "header": {"$": "dict", "items": []},
        "value": value,
        "arrays": list(arrays),
        **over,
    }


def refused(data, *fragments):
    with pytest.raises(StoreError) as exc:
        store.loads(data, "blocks/block-000007.zip")
    msg = str(exc.value)
    assert msg.startswith("blocks/block-000007.zip: ") and "\n" not in msg, msg
    for f in fragments:
        assert f in msg, msg
    return msg


class Touch:
    """A pickle payload that creates a file when it is unpickled."""

    def __init__(self, path):
        self.path = path

    def __reduce__(self):
        return (pathlib.Path.touch, (self.path,))


def test_a_pickle_is_refused_and_not_run(tmp_path):
    live = pickle.dumps(Touch(tmp_path / "proof"))
    pickle.loads(live)  # the payload is live: unpickling it creates the file
    assert (tmp_path / "proof").exists()
    target = tmp_path / "pwned"
    refused(pickle.dumps(Touch(target)), "not a zip archive")
    # the same payload as an object array inside an otherwise well-formed file
    npy = io.BytesIO()
    np.save(npy, np.array([Touch(target)], dtype=object), allow_pickle=True)
    data = craft(
        manifest({"$": "ndarray", "index": 0, "dtype": "|O", "shape": [1]}, ["arrays/000000.npy"]),
        {"arrays/000000.npy": npy.getvalue()},
    )
    refused(data, "arrays/000000.npy", "dtype object")
    # or as the manifest itself
    refused(craft(pickle.dumps(Touch(target))), store.MANIFEST, "damaged")
    assert not target.exists()


@pytest.mark.parametrize(
    "name", ["os.system", "subprocess.Popen", "builtins.eval", "tests.never_imported.Thing"]
)
def test_an_unknown_type_name_is_refused_without_importing_it(name):
    node = {"$": "dataclass", "name": name, "fields": {"args": {"$": "tuple", "items": ["id"]}}}
    refused(craft(manifest(node)), f"unknown type name {name!r}")
    refused(craft(manifest({"$": "model", "name": name, "data": {}})), "unknown type name")
    assert "tests.never_imported" not in sys.modules


def test_a_model_name_is_not_a_dataclass_name():
    refused(craft(manifest({"$": "model", "name": "tests.store.Point", "data": {}})), "model")


def _edit_value(value, edit):
    data = store.dumps(value)
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        m = json.loads(zf.read(store.MANIFEST))
        members = {n: zf.read(n) for n in zf.namelist() if n != store.MANIFEST}
    edit(m)
    return craft(m, members)


def test_a_wrong_field_set_is_refused():
    def drop(m):
        del m["value"]["fields"]["y"]

    def add(m):
        m["value"]["fields"]["z"] = 1

    refused(_edit_value(Point(1.0, 2.0), drop), "tests.store.Point", "missing ['y']")
    refused(_edit_value(Point(1.0, 2.0), add), "unexpected ['z']")


def test_a_bad_model_dump_is_refused():
    def bad(m):
        m["value"]["data"]["items"][0][1] = "three"

    refused(_edit_value(Model(a=3, b=(), c={}), bad), "tests.store.Model", "a:")


@pytest.mark.parametrize(
    ("node", "fragment"),
    [
        ({"$": "eval", "code": "1"}, "unknown node type 'eval'"),
        ({"no": "tag"}, "not a value node"),
        ({"$": "tuple", "items": [], "extra": 1}, "has keys"),
        ({"$": "float", "bits": "xyz"}, "16 hex digits"),
        ({"$": "dict", "items": [[1, 2], [1, 3]]}, "duplicate key 1"),
        ({"$": "dict", "items": [[[1], 2]]}, "unhashable"),
        ({"$": "dict", "items": [[1]]}, "[key, value] pair"),
        ({"$": "ndarray", "index": 0, "dtype": "<f8", "shape": [1]}, "not one of the 0 arrays"),
        ({"$": "scalar", "dtype": "|O", "bytes": ""}, "not a plain-data dtype"),
        ({"$": "scalar", "dtype": "<f8", "bytes": "00"}, "1 bytes for a <f8 scalar"),
    ],
)
def test_malformed_nodes_are_refused(node, fragment):
    refused(craft(manifest({"$": "tuple", "items": [node]})), "value[0]", fragment)


def test_damaged_and_foreign_archives_are_refused():
    good = store.dumps({"a": np.arange(10.0), "b": Point(1.0, 2.0)})
    refused(b"", "not a zip archive")
    refused(b"garbage" * 100, "not a zip archive")
    for cut in (1, 10, 100, len(good) // 2, len(good) - 30, len(good) - 1):
        refused(good[:cut])  # truncated
    # one byte flipped inside the array's data: the member's CRC-32 no longer matches
    with zipfile.ZipFile(io.BytesIO(good)) as zf:
        info = zf.getinfo("arrays/000000.npy")
    at = info.header_offset + 30 + len(info.filename) + info.file_size - 1
    flipped = bytearray(good)
    flipped[at] ^= 0x01
    refused(bytes(flipped), "arrays/000000.npy", "damaged")
    npy = io.BytesIO()
    np.save(npy, np.arange(3.0))
    arr = {"arrays/000000.npy": npy.getvalue()}
    ok = manifest({"$": "ndarray", "index": 0, "dtype": "<f8", "shape": [3]}, arr)
    assert np.array_equal(store.loads(craft(ok, arr)).value, np.arange(3.0))
    refused(craft({**ok, "format": "other"}, arr), "format 'other'")
    refused(craft({**ok, "version": 2}, arr), "version 2")
    refused(craft({**ok, "version": True}, arr), "version True")
    refused(craft({k: v for k, v in ok.items() if k != "header"}, arr), "has keys")
    refused(craft(ok, {**arr, "extra.bin": b"x"}), "unexpected ['extra.bin']")
    refused(craft(ok), "missing ['arrays/000000.npy']")
    refused(craft(ok, arr, zipfile.ZIP_DEFLATED), "compressed")
    shape = manifest({"$": "ndarray", "index": 0, "dtype": "<f8", "shape": [2]}, arr)
    refused(craft(shape, arr), "the manifest says <f8 [2]")
    dtype = manifest({"$": "ndarray", "index": 0, "dtype": "<f4", "shape": [3]}, arr)
    refused(craft(dtype, arr), "the manifest says <f4 [3]")
    refused(craft(manifest(None, arr), arr), "not used")
    twice = {"$": "tuple", "items": [ok["value"], ok["value"]]}
    refused(craft(manifest(twice, arr), arr), "used twice")
    refused(craft({"$": "dict", "items": []}, arr), "has keys")
    refused(craft(b'{"format": NaN}'), "NaN is not JSON")
    refused(craft(b'{"format": 1, "format": 2}'), "duplicate key 'format'")
    refused(craft(b"[" * 100_000 + b"]" * 100_000), "nested too deeply")
    refused(craft(b"\xff\xfe"), "damaged")
    bad_npy = {"arrays/000000.npy": npy.getvalue()[:-8]}
    refused(craft(ok, bad_npy), "data bytes")
    refused(craft(ok, {"arrays/000000.npy": b"not npy"}), "not a .npy array")


def test_load_names_the_path(tmp_path):
    path = tmp_path / "x.zip"
    path.write_bytes(b"junk")
    with pytest.raises(StoreError, match=str(path)):
        store.load(path)
    with pytest.raises(StoreError, match="cannot read"):
        store.load(tmp_path / "missing.zip")
    path.write_bytes(store.dumps([1.5]))
    assert store.load(path).value == [1.5]


# ---------------------------------------------------------------------------------------------
# every experiment's block result


def _block(name, runs, *overrides):
    plan = plan_batch(name, n_runs=max(runs) + 1, overrides=list(overrides))
    return plan.experiment.run_block(plan.scenario, 1, runs)


def test_paper000_block():
    block = _block(
        "paper-000/test-1",
        (0, 1, 2),
        "passage.duration_s=100",
        "passage.closest_approach_time_s=50",
        "report.single_passages=2",
        "report.routes_max=2",
    )
    assert block.routes and block.single  # the optional parts are there
    same(roundtrip(block).value, block)


def test_paper001_block():
    block = _block(
        "paper-001/replica",
        (0, 1),
        "systematic_speeds_m_s=[0.3]",
        "current_speeds_m_s=[0.5]",
        "betas_deg=[20.0]",
    )
    assert block.tracks
    same(roundtrip(block).value, block)


@pytest.mark.slow
def test_paper003_block():
    block = _block("paper-003/test-1", (0, 1), "report.readings=all", "report.routes_max=1")
    assert block.routes and block.single and len(block.labels) == 16
    same(roundtrip(block).value, block)


@pytest.mark.parametrize("name", ["paper-004/table-1", "paper-004/near-beacon"])
def test_paper004_block(name):
    block = _block(name, (0, 1), "path.duration_s=20.0", "filters.train_paths=200")
    same(roundtrip(block).value, block)


def test_paper004_seabed_shift_block():
    block = _block("paper-004/seabed-shift", (0, 1), "steps=3")
    assert set(block) == {"one_attitude", "turning"}
    assert block["turning"]["error_m"].shape == (2, 3, 3) and block["turning"]["ok"].dtype == bool
    same(roundtrip(block).value, block)


def test_trn_relief_block():
    block = _block(
        "trn/relief",
        (3, 4),
        "track.duration_s=5",
        "sweep.relief_std_m=[1.0]",
        "sweep.map_sigma_m=[0.1]",
    )
    assert block["final_m"].shape == (2, 1, 3) and block["sq_err_sum"].shape == (1, 3, 6)
    same(roundtrip(block).value, block)


def test_acoustics_sound_speed_block():
    block = _block(
        "acoustics/sound-speed", (3, 4), "usbl.fixes=5", "modem.horizontal_ranges_m=[300]"
    )
    assert block["usbl_horizontal_m"].shape == (2, 5, 3)
    assert block["modem_error_m"].shape == (2, 3, 3)
    assert block["usbl_present"].dtype == bool
    same(roundtrip(block).value, block)


def test_coop_team_block():
    block = _block("coop/team", (3, 4), "team.duration_s=20")
    assert block["mean_m"].shape == (2, 1, 5, 4) and block["sq_err_sum"].shape == (1, 5, 4, 5)
    assert block["lost"].dtype == np.int64 and block["nees_count"].dtype == np.int64
    same(roundtrip(block).value, block)


def test_accuracy_block():
    assert _block("paper-000/accuracy", (0,)) is None
    assert roundtrip(None).value is None


def test_autopilot_block():
    from tasks.vehicle import autopilot as va

    scn = plan_batch("vehicle/autopilot").scenario
    trial = va.fly_trial(scn, 1.0, lambda t: 0.0, lambda t: scn.depth_m, lambda t: scn.speed_to_m_s)
    block = {name: trial for name in ("heading", "depth", "speed", "current")}
    same(roundtrip(block).value, block)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["mission/short", "mission/correction", "mission/swarm"])
def test_mission_blocks(name):
    block = _block(name, (0,), "timing.max_duration_s=10")
    flights = block[0].flights.values() if name != "mission/short" else block
    assert all(f.vehicles and f.lead.ticks and f.lead.summary for f in flights)
    got = roundtrip(block).value
    same(got, block)


@pytest.mark.slow
def test_seed004_mission_block():
    block = _block(
        "mission/seed004",
        (0,),
        "timing.max_duration_s=10",
        "seed004.duration_s=10",
        "seed004.train_paths=200",
        "navigation.filter=cmnf",
    )
    assert block[0].metrics["cmnf"]["j_k"] and block[0].failed == {"cmnf": None}
    assert block[0].flights["cmnf"].lead.fixes["doa"]["accepted"].values.any()
    same(roundtrip(block).value, block)


@pytest.mark.slow
def test_trn_mission_block():
    block = _block("mission/trn", (0,), "timing.max_duration_s=70", "report.figures=false")
    r = block[0]
    assert r.failed is None and len(r.t_s) > 5 and r.track and set(r.errors_m) >= {"trn_pf"}
    assert r.flight is not None and r.flight.lead.ticks["trn_pmf_P"].values.shape[1:] == (2, 2)
    same(roundtrip(block).value, block)


def test_fleet_block():
    block = _block(
        "fleet/survey",
        (0, 1),
        "timing.max_duration_s=20",
        "plan.lanes=1",
        "plan.lane_length_m=20",
    )
    assert block.runs.tolist() == [0, 1] and block.tracks["truth_pos"].shape[1:] == (2, 3)
    same(roundtrip(block).value, block)


def test_every_experiment_class_has_a_block_test_above():
    tested = {
        "StraightPassageExperiment",
        "Paper001Replica",
        "AccuracyExperiment",
        "AutopilotTrials",
        "MissionExperiment",
        "CorrectionExperiment",
        "SwarmExperiment",
        "SquareExperiment",
        "Paper004Experiment",
        "SeabedShiftExperiment",
        "Seed004Experiment",
        "TrnExperiment",
        "TrnReliefExperiment",
        "SoundSpeedExperiment",
        "CoopExperiment",
        "FleetExperiment",
    }
    assert {type(e).__name__ for e in registry.all_experiments()} <= tested


@pytest.mark.slow
def test_the_largest_mission_block_grows_within_the_block_file_ceiling():
    """A block file is refused above ``runner.block_file_limit`` (issue 21), whose part that
    grows with a mission's length is BLOCK_FILE_MEMORY_FACTOR x the memory estimate per control
    tick. The most vehicles a mission flies (mission/swarm: a leader and 4 followers) must grow
    by less: measured here as the bytes a block gains from 10 s to 30 s of flight."""
    from tasks.closed_loop.experiment import BYTES_PER_TICK
    from tasks.core import run_folder, runner

    sizes = []
    for duration_s in (10, 30):
        plan = plan_batch(
            "mission/swarm", 1, 1, [f"timing.max_duration_s={duration_s}", "followers.count=4"]
        )
        block = plan.experiment.run_block(plan.scenario, 1, plan.blocks[0])
        sizes.append(len(store.dumps(block, run_folder.block_header(plan, 0))))
        assert sizes[-1] <= plan.block_file_limit_b
    per_tick = (sizes[1] - sizes[0]) / (20.0 / plan.scenario.timing.control_tick_s)
    assert per_tick < runner.BLOCK_FILE_MEMORY_FACTOR * BYTES_PER_TICK, per_tick
