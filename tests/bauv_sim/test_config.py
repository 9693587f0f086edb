"""Configuration errors name the field, the value and what is allowed."""

import pytest
from pydantic import Field

from bauv_sim.config import Config, apply_overrides, load_config, parse_override
from bauv_sim.errors import ConfigError


class Usbl(Config):
    period_s: float = Field(5.0, gt=0)
    sigma_range_m: float = Field(0.2, ge=0)
    noise: str = "uniform"


class Scenario(Config):
    usbl: Usbl = Usbl()


def test_overrides_parse_toml_values():
    assert parse_override("usbl.period_s=20") == (["usbl", "period_s"], 20)
    assert parse_override("a.b=uniform") == (["a", "b"], "uniform")
    assert parse_override("a=[1, 2]") == (["a"], [1, 2])
    cfg = load_config(Scenario, overrides=["usbl.period_s=20", "usbl.noise=gaussian"])
    assert cfg.usbl.period_s == 20.0 and cfg.usbl.noise == "gaussian"


def test_frozen():
    cfg = load_config(Scenario)
    with pytest.raises(Exception, match="frozen"):
        cfg.usbl.period_s = 3.0  # type: ignore[misc]


@pytest.mark.parametrize(
    ("override", "pattern"),
    [
        ("usbl.sigma_range_m=-1", r"usbl\.sigma_range_m = -1: .*greater than or equal to 0"),
        ("usbl.bogus=1", r"unknown field 'usbl\.bogus'"),
        ("usbl.period_s=nan", r"usbl\.period_s = nan: .*finite"),
        ("usbl.period_s=inf", r"usbl\.period_s = inf: .*finite"),
    ],
)
def test_errors_are_one_clear_line(override, pattern):
    with pytest.raises(ConfigError, match=pattern) as info:
        load_config(Scenario, overrides=[override])
    assert "\n" not in str(info.value)


def test_bad_override_syntax():
    with pytest.raises(ConfigError, match="KEY=VALUE"):
        apply_overrides({}, ["novalue"])
    with pytest.raises(ConfigError, match="is a value, not a table"):
        apply_overrides({"a": 1}, ["a.b=2"])


def test_overrides_address_array_elements():
    data = {"wps": [{"x": 1}, {"x": 2}]}
    assert apply_overrides(data, ["wps.1.x=5"])["wps"] == [{"x": 1}, {"x": 5}]
    with pytest.raises(ConfigError, match=r"wps\.2: index must be 0\.\.1"):
        apply_overrides(data, ["wps.2.x=5"])
