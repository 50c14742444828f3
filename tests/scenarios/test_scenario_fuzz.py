"""Scenario files as hostile input: :func:`read_scenario_file` (and ``load_scenario``).

The built-in scenario files are damaged in seeded random ways (bytes flipped, truncated,
lines deleted or duplicated, values replaced by wrong types, huge numbers, nan, long
strings, deep nesting, binary junk) and hostile files are made by hand (a FIFO,
/dev/zero, a directory, link loops, oversized, not UTF-8, names that are too long or hold
a path separator). Every case must either load to a valid scenario or raise
:class:`ScenarioError` with one printable line that quotes no line of the file longer
than :data:`SHOWN_CHARS` characters; any other exception type fails the test.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from importlib import resources
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from brake_sim_ros.errors import ScenarioError
from brake_sim_ros.scenarios import builtin_names, load_scenario, loader
from brake_sim_ros.scenarios.checker import SHOWN_CHARS
from brake_sim_ros.scenarios.files import MAX_SCENARIO_BYTES
from brake_sim_ros.scenarios.loader import (
    BUILTIN_PACKAGE,
    MAX_NAME_CHARS,
    MAX_NESTING,
    read_scenario_file,
)
from brake_sim_ros.scenarios.types import Scenario

BUILTIN = {
    name: resources.files(BUILTIN_PACKAGE).joinpath(f"{name}.toml").read_bytes()
    for name in builtin_names()
}
FUZZ = settings(
    max_examples=int(os.environ.get("FUZZ_EXAMPLES", "150")),
    deadline=None,
    derandomize=True,  # the same cases every run: a failure reproduces
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def _check_message(message: str, content: bytes) -> None:
    """One printable, bounded line that quotes no line of ``content`` longer than
    SHOWN_CHARS characters."""
    assert "\n" not in message and message.isprintable(), repr(message)
    assert len(message) < 1000, message
    for line in content.decode("utf-8", "replace").splitlines():
        line = line.strip()
        if len(line) > SHOWN_CHARS:
            assert line not in message, (line, message)


def _load(path: Path, content: bytes) -> Scenario | str:
    """The scenario, or the ScenarioError's message (checked); nothing else may escape."""
    try:
        scenario = read_scenario_file(path)
    except ScenarioError as exc:
        _check_message(str(exc), content)
        return str(exc)
    assert isinstance(scenario, Scenario)
    assert 0 < len(scenario.name) <= MAX_NAME_CHARS and "/" not in scenario.name
    return scenario


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("fuzz") / "scenario.toml"


def _write_and_load(path: Path, content: bytes) -> Scenario | str:
    path.write_bytes(content)
    return _load(path, content)


# --- the built-in files load, and every byte of them can be damaged ---------------------------
def test_the_builtin_files_load_through_the_checked_reader(tmp_path):
    for name, content in BUILTIN.items():
        result = _write_and_load(tmp_path / f"{name}.toml", content)
        assert isinstance(result, Scenario) and result.name == name


builtin_file = st.sampled_from(sorted(BUILTIN))


@FUZZ
@given(name=builtin_file, data=st.data())
def test_flipped_bytes(scratch, name, data):
    content = bytearray(BUILTIN[name])
    n = data.draw(st.integers(1, 8))
    for _ in range(n):
        i = data.draw(st.integers(0, len(content) - 1))
        content[i] = data.draw(st.integers(0, 255))
    _write_and_load(scratch, bytes(content))


@FUZZ
@given(name=builtin_file, data=st.data())
def test_truncated_and_junk_appended(scratch, name, data):
    content = BUILTIN[name]
    cut = data.draw(st.integers(0, len(content)))
    junk = data.draw(st.binary(max_size=64))
    _write_and_load(scratch, content[:cut] + junk)


@FUZZ
@given(name=builtin_file, data=st.data())
def test_lines_deleted_duplicated_and_swapped(scratch, name, data):
    lines = BUILTIN[name].splitlines(keepends=True)
    for _ in range(data.draw(st.integers(1, 4))):
        i = data.draw(st.integers(0, len(lines) - 1))
        action = data.draw(st.sampled_from(["delete", "duplicate", "move"]))
        line = lines.pop(i) if action != "duplicate" else lines[i]
        if action != "delete":
            lines.insert(data.draw(st.integers(0, len(lines))), line)
    _write_and_load(scratch, b"".join(lines))


HOSTILE_VALUES = [
    "nan",
    "-nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1e400",
    "5e-324",
    "0",
    "0.0",
    "-0.0",
    "9223372036854775807",
    "-9223372036854775808",
    "true",
    "1979-05-27",
    "1979-05-27T07:32:00Z",
    "07:32:00",
    "[]",
    "{}",
    '""',
    '"../../etc/passwd"',
    "[1, 2, 3]",
    "[[1], [2]]",
    "[{ a = 1 }]",
    '["left", "left"]',
    '["left", ["right"]]',
    '["stop_time", 1]',
    "{ a = 1 }",
    "{ times_s = [0.0], forces_n = [1.0] }",
    "[" * 40 + "]" * 40,
    "1" * 5000,
    '"' + "x" * 300 + '"',
    '"""\n' + "a long line inside a multi-line string, quoted nowhere\n" * 3 + '"""',
]
_hostile_value = st.one_of(
    st.sampled_from(HOSTILE_VALUES),
    st.floats(allow_nan=True, allow_infinity=True)
    .map(repr)
    .map(lambda r: {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(r, r)),
    st.integers(-(2**70), 2**70).map(str),
    st.text(max_size=40).map(lambda t: '"' + t.replace("\\", "/").replace('"', "'") + '"'),
)


@FUZZ
@given(name=builtin_file, value=_hostile_value, data=st.data())
def test_values_replaced_by_wrong_types_and_extremes(scratch, name, value, data):
    lines = BUILTIN[name].decode().splitlines()
    assignments = [i for i, line in enumerate(lines) if " = " in line and line[0] != "#"]
    i = data.draw(st.sampled_from(assignments))
    key = lines[i].split(" = ")[0]
    lines[i] = f"{key} = {value}"
    _write_and_load(scratch, "\n".join(lines).encode("utf-8", "surrogatepass"))


SECTIONS = [
    "[parameters.friction]\ncoefficient",
    "[parameters.driveline]\ncoupling_stiffness_n_m_per_rad",
    "[parameters.driveline]\ninitial_speed_rad_s",
    "[parameters.shoe]\nmass_kg",
    "[parameters]\nshoe",
    "[defects.left]\npivot_radius_change_pct",
    "[defects.right]\ninitial_angle_deg",
    "[defects.left]\nactuation_share",
    "[defects]\nleft",
    "[solver]\nmax_step_s",
    "[solver]\nrtol",
    "[solver]\nmethod",
    "[solver]\npreset",
    "[solver]\ndt_s",
    "[needs]\noutputs",
    "[needs]\nshoes",
    "[needs]\nlevel",
    "[needs]\naccuracy",
    "[model]\nshoes",
    "[model]\nrigid_coupling",
    "[actuation]\npeak_force_n",
    "[actuation]\nstart_s",
    "[actuation]\nfull_s",
    "[actuation]\nprofile",
    '[actuation]\nprofile = "piecewise"\nleft',
    '[actuation]\nprofile = "piecewise"\nright = { times_s = [0.0], forces_n = [1.0] }\nleft',
    "[actuation.left]\ntimes_s",
    "actuation",
    "seed",
    "duration_s",
    "sample_rate_hz",
    "name",
    "description",
]


def _with_value(section: str, value: str) -> bytes:
    text = f"{section} = {value}\n"
    if section != "name":
        text = f'name = "h"\n{text}'
    return text.encode("utf-8", "surrogatepass")


def test_every_key_of_a_scenario_takes_every_hostile_value(scratch):
    for section in SECTIONS:
        for value in HOSTILE_VALUES:
            _write_and_load(scratch, _with_value(section, value))


@FUZZ
@given(section=st.sampled_from(SECTIONS), value=_hostile_value)
def test_every_key_of_a_scenario_takes_random_values(scratch, section, value):
    _write_and_load(scratch, _with_value(section, value))


@FUZZ
@given(junk=st.binary(min_size=1, max_size=512))
def test_binary_junk(scratch, junk):
    _write_and_load(scratch, junk)


# --- hand-made hostile files -----------------------------------------------------------------
def _deep(depth: int) -> dict[str, str]:
    return {
        "array": "name = 'x'\na = " + "[" * depth + "]" * depth,
        "inline table": "name = 'x'\na = " + "{b = " * depth + "1" + "}" * depth,
        "table header": "name = 'x'\n[" + ".".join(["x"] * depth) + "]",
        "dotted key": "name = 'x'\n" + ".".join(["x"] * depth) + " = 1",
    }


@pytest.mark.parametrize("depth", [MAX_NESTING + 1, 2_000])
@pytest.mark.parametrize("form", sorted(_deep(1)))
def test_deep_nesting_is_one_line(tmp_path, depth, form):
    content = _deep(depth)[form].encode()
    message = _write_and_load(tmp_path / "deep.toml", content)
    assert isinstance(message, str) and "nested too deeply" in message, message


@pytest.mark.parametrize("depth", [MAX_NESTING - 2])
@pytest.mark.parametrize("form", sorted(_deep(1)))
def test_nesting_within_the_limit_is_left_to_the_key_checks(tmp_path, depth, form):
    message = _write_and_load(tmp_path / "deep.toml", _deep(depth)[form].encode())
    assert isinstance(message, str) and "unknown key" in message, message


def _limited_memory() -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (3 << 30, 3 << 30))


@pytest.fixture(scope="module")
def megabyte_refusals() -> dict[str, str]:
    """Each form of :func:`_deep` at half a million levels, read in one child process with
    3 GB of address space (one start-up for the four): tomllib would recurse past the
    stack, or (a dotted key) take memory quadratic in its parts. What the child printed
    for each form (its error's line), or its failure."""
    forms = sorted(_deep(1))
    code = (
        "import json, sys\n"
        "from brake_sim_ros.errors import ScenarioError\n"
        "from brake_sim_ros.scenarios.loader import parse_scenario\n"
        "said = {}\n"
        "for form, text in json.loads(sys.stdin.read()).items():\n"
        "    try:\n"
        "        parse_scenario(text, 'deep.toml')\n"
        "        said[form] = 'read without an error'\n"
        "    except ScenarioError as exc:\n"
        "        said[form] = str(exc)\n"
        "print(json.dumps(said))\n"
    )
    deep = _deep(MAX_SCENARIO_BYTES // 2)
    texts = {form: deep[form][:MAX_SCENARIO_BYTES] for form in forms}
    r = subprocess.run(
        [sys.executable, "-c", code],
        input=json.dumps(texts),
        capture_output=True,
        text=True,
        timeout=240,
        preexec_fn=_limited_memory,
    )
    if r.returncode != 0 or "Traceback" in r.stderr:
        return {form: f"exit {r.returncode}: {r.stderr[-2000:]}" for form in forms}
    return json.loads(r.stdout)


@pytest.mark.parametrize("form", sorted(_deep(1)))
def test_a_megabyte_of_nesting_is_refused_before_parsing(megabyte_refusals, form):
    """Half a million levels: refused in one line before tomllib reads them."""
    said = megabyte_refusals[form]
    assert said.startswith("deep.toml: nested too deeply"), said


@pytest.mark.parametrize(
    ("name", "fragment"),
    [
        ("a" * (MAX_NAME_CHARS + 1), "a string of 256 characters"),
        ("a" * 100_000, "a string of 100000 characters"),
        ("../etc/passwd", "without '/'"),
        ("a\\\\b", "without '/' or '\\'"),
        ("..", "printable characters"),
        ("", "1 to 255"),
        ("tab\\there", "printable"),
        ("\\u001b[31mred", "printable"),
    ],
)
def test_bad_scenario_names_are_refused_with_what_is_allowed(tmp_path, name, fragment):
    content = f'name = "{name}"\n'.encode()
    message = _write_and_load(tmp_path / "n.toml", content)
    assert isinstance(message, str) and "key 'name'" in message and fragment in message, message


def test_a_name_of_the_largest_length_loads(tmp_path):
    name = "é" * MAX_NAME_CHARS
    result = _write_and_load(tmp_path / "n.toml", f'name = "{name}"\n'.encode())
    assert isinstance(result, Scenario) and result.name == name


def test_size_limit_before_parsing(tmp_path):
    at_limit = b'name = "big"\n' + b"#" * (MAX_SCENARIO_BYTES - 14) + b"\n"
    assert len(at_limit) == MAX_SCENARIO_BYTES
    assert isinstance(_write_and_load(tmp_path / "ok.toml", at_limit), Scenario)
    over = at_limit + b"\n"
    message = _write_and_load(tmp_path / "big.toml", over)
    assert isinstance(message, str) and "larger than 1048576 bytes (1 MiB)" in message
    with pytest.raises(ScenarioError, match="allowed at most 1048576 bytes"):
        loader.parse_scenario(over.decode(), "text")  # text from elsewhere: the same limit


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (b'name = "x"\ndescription = "\xff\xfe"\n', "not UTF-8 text"),
        ('name = "x"\n'.encode("utf-16"), "not UTF-8 text"),
        (b"\x00" * 100, "contains NUL characters"),
        (b"\x7fELF\x02\x01\x01" + bytes(range(256)), "not UTF-8 text"),
        (b"", "key 'name' is missing"),
        (b"a = " + b"1" * 5000, "too many digits"),
        (b"[a]\nx = 1\n[a]\n", "Cannot declare ('a',) twice (at line 3, column 3)"),
        (b'name = "x"\nduration_s = 1979-05-27T07:32:00Z\n', "= a datetime value is"),
        (b'name = "x"\n[actuation]\nstart_s = 0.0\n', "strictly increasing"),
    ],
)
def test_broken_content_is_one_line(tmp_path, content, fragment):
    message = _write_and_load(tmp_path / "b.toml", content)
    assert isinstance(message, str) and fragment in message, message


def test_a_file_larger_than_its_stat_size_is_still_bounded(tmp_path, monkeypatch):
    """Files in /proc say they hold 0 bytes: the limit holds while reading too."""
    path = tmp_path / "big.toml"
    path.write_bytes(b"#" * (MAX_SCENARIO_BYTES + 1))
    real_fstat = os.fstat

    def fstat_says_empty(fd):
        info = real_fstat(fd)
        return os.stat_result((*info[:6], 0, *info[7:]))

    monkeypatch.setattr(os, "fstat", fstat_says_empty)
    with pytest.raises(ScenarioError, match=r"larger than 1048576 bytes"):
        read_scenario_file(path)


@pytest.mark.parametrize("form", sorted(_deep(1)))
def test_nesting_is_refused_before_tomllib_sees_it(monkeypatch, form):
    def refuse(text):
        raise AssertionError("tomllib was given a too deeply nested text")

    monkeypatch.setattr(loader.tomllib, "loads", refuse)
    with pytest.raises(ScenarioError, match="nested too deeply"):
        loader.parse_scenario(_deep(MAX_NESTING + 1)[form], "deep.toml")


def test_a_utf8_byte_order_mark_is_dropped(tmp_path):
    result = _write_and_load(tmp_path / "bom.toml", b'\xef\xbb\xbfname = "bom"\n')
    assert isinstance(result, Scenario) and result.name == "bom"


def test_long_keys_and_values_are_described_not_quoted(tmp_path):
    long_key = "k" * 5000
    for content, fragment in (
        (f'name = "x"\n{long_key} = 1\n', "key '<a key of 5000 characters>' = 1"),
        (f'name = "x"\n[actuation]\nprofile = "{long_key}"\n', "a string of 5000 characters"),
        (f'name = "x"\n[{long_key}]\n[{long_key}]\n', "Cannot declare (...) twice"),
        (
            'name = "x"\nseed = "a sentence that is a little too long"\n',
            "a string of 36 characters",
        ),
    ):
        message = _write_and_load(tmp_path / "k.toml", content.encode())
        assert isinstance(message, str) and fragment in message, message


def test_special_files(tmp_path):
    cases = {
        "/dev/zero": "it is a character device",
        "/dev/null": "it is a character device",
        str(tmp_path): "it is a directory",
        str(tmp_path / "missing.toml"): "no such file",
    }
    loop = tmp_path / "loop.toml"
    loop.symlink_to(tmp_path / "loop2.toml")
    (tmp_path / "loop2.toml").symlink_to(loop)
    cases[str(loop)] = "Too many levels of symbolic links"
    dangling = tmp_path / "dangling.toml"
    dangling.symlink_to(tmp_path / "nowhere.toml")
    cases[str(dangling)] = "no such file"
    cases[str(tmp_path / "a\x00b.toml")] = "not a valid path"
    cases["x" * 5000 + ".toml"] = "File name too long"
    for path, fragment in cases.items():
        with pytest.raises(ScenarioError) as info:
            load_scenario(path)
        message = str(info.value)
        assert fragment in message and "\n" not in message and len(message) < 1000, message


def test_a_link_to_a_scenario_file_is_followed(tmp_path):
    real = tmp_path / "real.toml"
    real.write_bytes(BUILTIN["symmetric"])
    link = tmp_path / "link.toml"
    link.symlink_to(real)
    assert read_scenario_file(link).name == "symmetric"


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads a file of mode 000")
def test_an_unreadable_file(tmp_path):
    path = tmp_path / "secret.toml"
    path.write_bytes(BUILTIN["symmetric"])
    path.chmod(0)
    with pytest.raises(ScenarioError, match="Permission denied"):
        read_scenario_file(path)


def test_a_fifo_is_refused_at_once_without_a_writer(tmp_path):
    """In a child process: a reader that waits for the FIFO's writer would hang, and the
    timeout fails the test instead of hanging the suite."""
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    code = (
        "import sys\n"
        "from brake_sim_ros.errors import ScenarioError\n"
        "from brake_sim_ros.scenarios.loader import read_scenario_file\n"
        "try:\n"
        f"    read_scenario_file({str(fifo)!r})\n"
        "except ScenarioError as exc:\n"
        "    print(exc)\n"
    )
    r = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
    )
    assert r.stdout.strip().endswith("it is a FIFO (named pipe); allowed a regular file")


@pytest.mark.parametrize(
    ("name", "fragment"),
    [
        ("x" * 5000, "unknown scenario a string of 5000 characters: allowed a path"),
        ("nul\x00name", "unknown scenario 'nul\\x00name': allowed a path"),
        ("", "unknown scenario '': allowed a path"),
        ("symmetric ", "unknown scenario 'symmetric ': allowed a path"),
    ],
)
def test_hostile_names_given_to_load_scenario(name, fragment):
    """What the node's ~/reset service may be sent: one line, no OSError or ValueError."""
    with pytest.raises(ScenarioError) as info:
        load_scenario(name)
    assert str(info.value).startswith(fragment), str(info.value)
