"""``bauv show NAME --doc``: every field of every scenario, with description, unit and range."""

import pytest
from click.testing import CliRunner
from pydantic import BaseModel

from bauv_sim.config import load_config, to_plain
from tasks.core import cli, registry
from tasks.core.doc import unit_of


def _leaves(plain, prefix=""):
    """Leaf paths of a resolved scenario's plain data (a list of tables: its first item)."""
    for k, v in plain.items():
        if isinstance(v, dict):
            yield from _leaves(v, f"{prefix}{k}.")
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            yield from _leaves(v[0], f"{prefix}{k}[].")
        else:
            yield f"{prefix}{k}"


def _descriptions(model, value):
    """(field name, description) of every described field, walked over the values."""
    for name, f in type(value).model_fields.items():
        v = getattr(value, name)
        if f.description:
            yield name, f.description
        if isinstance(v, BaseModel):
            yield from _descriptions(type(v), v)
        elif isinstance(v, (list, tuple)) and v and isinstance(v[0], BaseModel):
            yield from _descriptions(type(v[0]), v[0])


@pytest.mark.parametrize("name", [e.name for e in registry.all_experiments()])
def test_doc_lists_every_field_with_its_description(name):
    exp = registry.get(name)
    res = CliRunner().invoke(cli.cli, ["show", name, "--doc"])
    assert res.exit_code == 0, res.output
    text = res.output
    scn = load_config(exp.scenario_type, exp.preset, (), ())
    lines = text.splitlines()
    for path in _leaves(to_plain(scn)):
        leaf = path.rsplit(".", 1)[-1]
        hits = [ln for ln in lines if ln.strip().startswith(f"{leaf} = ")]
        assert hits, f"{name}: {path} missing"
        unit = unit_of(leaf)
        if unit is not None:
            assert any(f"unit: {unit}" in h for h in hits), (path, hits)
    for field, desc in _descriptions(exp.scenario_type, scn):
        assert desc in text, f"{name}: description of {field} missing"


def test_doc_shows_ranges_units_and_choices():
    text = CliRunner().invoke(cli.cli, ["show", "mission/survey", "--doc"]).output
    lines = [ln.strip() for ln in text.splitlines()]
    # the current's speed: 0 <= v <= 5 m/s (tasks.closed_loop / bauv_sim.currents Field)
    assert "speed_m_s = 0.25  (unit: m/s; float; >= 0, <= 5)" in lines
    # a Literal lists its choices; a navigator sigma is positive, in degrees
    assert any(ln.startswith("steer_on = 'ekf'  (one of 'ekf', 'dr')") for ln in lines)
    assert any(
        ln.startswith("sigma_heading_deg = ") and "unit: deg" in ln and "> 0" in ln for ln in lines
    )
    # an override shows its value
    res = CliRunner().invoke(
        cli.cli, ["show", "mission/survey", "--doc", "--set", "navigation.steer_on='dr'"]
    )
    assert any(ln.strip().startswith("steer_on = 'dr'") for ln in res.output.splitlines())


@pytest.mark.parametrize(
    ("name", "unit"),
    [
        ("speed_m_s", "m/s"),
        ("period_s", "s"),
        ("sigma_m", "m"),
        ("heading_deg", "deg"),
        ("current_walk_m_s_per_sqrt_s", "m/s/sqrt(s)"),
        ("slope", None),
        ("runs", None),
    ],
)
def test_unit_from_the_field_name(name, unit):
    assert unit_of(name) == unit
