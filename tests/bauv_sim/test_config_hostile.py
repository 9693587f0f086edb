"""Hostile scenario input (issue 21): nesting, huge arrays and strings are refused in one line
before tomllib or pydantic recurse; way-point errors are one line without pydantic's noise; the
loader's arguments are type-checked."""

import sys
from pathlib import Path

import pytest
import tomli_w
from pydantic import Field

from bauv_sim.config import (
    MAX_ARRAY_ITEMS,
    MAX_NESTING,
    MAX_STRING_CHARS,
    MAX_TOML_BYTES,
    Config,
    check_toml_text,
    load_config,
    read_toml,
)
from bauv_sim.errors import ConfigError

DEEP = 5000


class Point(Config):
    east_m: float
    north_m: float
    depth_m: float = Field(3.0, ge=0)


class Route(Config):
    points: tuple[Point, ...] = Field((Point(east_m=0, north_m=0),), min_length=1)
    offset_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    label: str = "a"
    anything: tuple = ()


def _one_line(exc: pytest.ExceptionInfo) -> str:
    text = str(exc.value)
    assert "\n" not in text, text
    return text


@pytest.mark.slow
@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        ("label = " + "[" * DEEP + "]" * DEEP, "nested more than 32 deep at line 1"),
        ("label = " + "{a = " * DEEP + "1" + "}" * DEEP, "nested more than 32 deep at line 1"),
        ("\n\nlabel = [1, " + "[" * DEEP + "]" * DEEP + "]", "nested more than 32 deep at line 3"),
        (".".join(["a"] * DEEP) + " = 1", "nested more than 32 deep at a.a.a..."),
        ("[" + ".".join(["a"] * DEEP) + "]\nb = 1", "nested more than 32 deep at a.a.a..."),
        ("anything = [" + "0," * (MAX_ARRAY_ITEMS + 1) + "]", "anything is an array of 100001"),
        ('label = "' + "x" * (MAX_STRING_CHARS + 1) + '"', "label is a string of 10001 char"),
    ],
    ids=["arrays", "inline-tables", "line-3", "dotted-keys", "header", "long-array", "long-str"],
)
def test_a_hostile_scenario_file_is_one_line(tmp_path, text, pattern):
    """Each of these made tomllib, merge or pydantic recurse past Python's limit (a 3,001-line
    RecursionError) or held arbitrarily large data; now one ConfigError naming the file."""
    f = tmp_path / "s.toml"
    f.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_config(Route, files=[f])
    line = _one_line(info)
    assert f"scenario file {str(f)!r}" in line and pattern in line, line


def test_a_file_larger_than_the_limit_is_refused_unread(tmp_path):
    f = tmp_path / "big.toml"
    f.write_bytes(b"# " + b"x" * MAX_TOML_BYTES + b"\n")
    with pytest.raises(ConfigError, match=f"larger than {MAX_TOML_BYTES} bytes"):
        read_toml(f)


@pytest.mark.parametrize(
    "override",
    [
        "label=" + "[" * DEEP + "]" * DEEP,
        "label=" + "{a=" * DEEP + "1" + "}" * DEEP,
        ".".join(["a"] * DEEP) + "=1",
    ],
    ids=["array", "inline-table", "dotted-key"],
)
def test_a_hostile_override_is_one_line(override):
    with pytest.raises(ConfigError, match="nested more than 32 deep") as info:
        load_config(Route, overrides=[override])
    _one_line(info)


def test_hostile_python_data_is_refused_before_it_is_merged():
    deep: list = []
    for _ in range(DEEP):
        deep = [deep]
    with pytest.raises(ConfigError, match="base: tables or arrays nested more than 32") as info:
        load_config(Route, base={"anything": deep})
    _one_line(info)
    with pytest.raises(ConfigError, match="nested more than 32"):
        from bauv_sim.config import validate

        validate(Route, {"anything": deep})


def test_the_limit_is_the_stated_depth():
    """32 levels load; 33 are refused (the check is not off by one either way)."""
    ok = "label2 = " + "[" * MAX_NESTING + "]" * MAX_NESTING
    check_toml_text(ok, "t")
    with pytest.raises(ConfigError, match="at line 1"):
        check_toml_text("x = " + "[" * (MAX_NESTING + 1) + "]" * (MAX_NESTING + 1), "t")


@pytest.mark.parametrize(
    "text",
    [
        'a = "' + "[" * 40 + '"',
        "a = '" + "[{" * 40 + "'",
        "# " + "[" * 40 + "\na = 1",
        'a = """\n' + "[" * 40 + '\n"""',
        "a = '''\n" + "[" * 40 + "'''",
        'a = "\\"' + "[" * 40 + '"',  # escaped quote inside a basic string
        'a = """x\\"""' + "[" * 40 + '"""',  # escaped quote inside a multi-line string
        'a = """' + "[" * 40 + '""""',  # closing delimiter after a quote of the content
        "a = '''" + "[" * 40 + "'''''",  # the same for a literal string
        'a = ""\nb = "' + "[" * 40 + '"',  # an empty string is not a multi-line one
    ],
)
def test_brackets_in_strings_and_comments_are_not_nesting(text):
    """Whatever tomllib reads as a string or a comment is not counted: each of these parses to
    at most one level, and the scanner agrees with the parser."""
    import tomllib

    tomllib.loads(text)  # valid TOML: the parser's own reading
    check_toml_text(text, "t")


def test_the_scanner_agrees_with_what_tomli_w_writes():
    """Independent truth: documents written by tomli_w (quotes, escapes, brackets, newlines and
    comment signs in strings) with arrays nested 1..MAX_NESTING deep parse with tomllib and pass
    the scanner; the same with one level more is refused."""
    import random
    import tomllib

    rnd = random.Random(21)
    alphabet = "[]{}\"'#\\\n ab=,."

    def doc(depth: int) -> str:
        value: object = "".join(rnd.choice(alphabet) for _ in range(30))
        for _ in range(depth):
            value = [value, "".join(rnd.choice(alphabet) for _ in range(10))]
        tail = "]]]" + "'" * 3 + '"' * 3 + "["
        return tomli_w.dumps({"s": {"k": value, "t": tail}})

    for depth in range(1, MAX_NESTING + 1):
        text = doc(depth)
        tomllib.loads(text)
        check_toml_text(text, "t")
    with pytest.raises(ConfigError, match="nested more than 32 deep"):
        check_toml_text(doc(MAX_NESTING + 1), "t")


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        ("points=[]", "points = []: must have at least 1 element, has 0"),
        ("points=5", "points = 5: must be an array of tables with east_m, north_m (required)"),
        ("points=[1, 2]", "points.0 = 1: must be a table with east_m, north_m (required) and "),
        ("points=[{east_m=1}]", "points.0.north_m: required field is missing"),
        ('points=[{east_m="x", north_m=1}]', "points.0.east_m = 'x': must be a number"),
        ("points=[{east_m=1, north_m=2, bogus=3}]", "unknown field 'points.0.bogus'"),
        ("points=[{east_m=1, north_m=2, depth_m=-1}]", "points.0.depth_m = -1: Input should"),
        ("offset_m=[1]", "offset_m = [1]: must be an array of 3 numbers, has 1"),
        ("offset_m=[1, 2, 3, 4]", "offset_m = [1, 2, 3, 4]: must have at most 3 elements"),
    ],
)
def test_waypoint_errors_are_one_line_without_pydantic_noise(override, expected):
    """A bad way-point gave a second line, "Tuple should have at least 1 item after validation,
    not 0" (pydantic's count of the valid elements): now one line naming the field, the value
    and what is allowed."""
    with pytest.raises(ConfigError) as info:
        load_config(Route, overrides=[override])
    line = _one_line(info)
    assert expected in line, line
    assert "Tuple should" not in line and "valid tuple" not in line and "dictionary" not in line


def test_several_problems_are_counted_on_the_one_line():
    with pytest.raises(ConfigError) as info:
        load_config(Route, overrides=["points=[1, 2, 3]"])
    assert _one_line(info).endswith("(and 2 more problems)")


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        ({"model": None}, r"model = None \(NoneType\): must be a Config subclass"),
        ({"model": dict}, r"model = <class 'dict'> \(type\): must be a Config subclass"),
        ({"model": Route()}, r"\(an instance\): must be a Config subclass"),
        ({"base": "label=x"}, r"base = 'label=x' \(str\): must be a mapping"),
        ({"base": [1]}, r"base = \[1\] \(list\): must be a mapping"),
        ({"files": "a.toml"}, r"files = 'a.toml': a single path; must be a list"),
        ({"files": Path("a.toml")}, r"a single path; must be a list of TOML files"),
        ({"files": None}, r"files = None \(NoneType\): must be a list"),
        ({"files": [3]}, r"files\[0\] = 3 \(int\): must be a path"),
        ({"overrides": "label=b"}, r"overrides = 'label=b': a single str; must be a list"),
        ({"overrides": None}, r"overrides = None \(NoneType\): must be a list"),
        ({"overrides": {"label": "b"}}, r"\(dict\): must be a list of KEY=VALUE"),
        ({"overrides": [5]}, r"overrides\[0\] = 5 \(int\): must be a KEY=VALUE string"),
    ],
)
def test_load_config_arguments_of_the_wrong_type(kwargs, pattern):
    """A None or a wrong type gave AttributeError/TypeError from inside, and a string given as
    the overrides list was read one character at a time ("override 'l': expected KEY=VALUE")."""
    args = {"model": Route} | kwargs
    with pytest.raises(ConfigError, match=pattern) as info:
        load_config(**args)
    _one_line(info)


def test_lists_and_tuples_of_overrides_and_paths_still_work(tmp_path):
    f = tmp_path / "a.toml"
    f.write_text('label = "from-file"\n')
    assert load_config(Route, files=(f,)).label == "from-file"
    assert load_config(Route, files=[str(f)], overrides=("label=b",)).label == "b"
    assert load_config(Route, overrides=iter(["label=c"])).label == "c"


if __name__ == "__main__":  # pragma: no cover
    sys.exit(pytest.main([__file__, "-q"]))
