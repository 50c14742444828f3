"""Every built-in detector has one registry entry, and each entry has every part: a
factory giving that detector, the saved form it claims, a line of help in the commands
that take it. An entry that lacks a part fails here."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import brake_sim_ros.detection as detection_package
from brake_sim_ros.cli import build_parser
from brake_sim_ros.cli.ros import monitor_parser
from brake_sim_ros.detection import saved
from brake_sim_ros.detection.detector import Detector
from brake_sim_ros.detection.registry import BUILTIN, ENTRIES, REGISTRY, help_text


def _help(argv: list[str], capsys) -> str:
    with pytest.raises(SystemExit):
        if argv[0] == "monitor":
            monitor_parser().parse_args(["--help"])
        else:
            build_parser().parse_args([*argv, "--help"])
    return " ".join(capsys.readouterr().out.split())


@pytest.mark.parametrize("entry", ENTRIES, ids=lambda e: e.name)
def test_every_entry_has_every_part(entry, capsys):
    detector = entry.make()
    assert isinstance(detector, Detector) and detector.name == entry.name
    assert BUILTIN[entry.name] is entry.make
    assert entry.summary and "\n" not in entry.summary
    assert entry.learns == (type(detector).fit is not Detector.fit)
    if entry.saved:
        assert entry.name in saved.SAVED and entry.name in saved._LOADERS
        assert type(detector) in saved._CODECS
    helps = {cmd: _help([cmd, "x"] if cmd != "monitor" else [cmd], capsys)
             for cmd in ("score", "fit", "monitor")}  # fmt: skip
    for cmd, text in helps.items():
        if entry.saved or cmd != "fit":
            assert f"{entry.name}: {' '.join(entry.summary.split())}" in text, cmd


def test_the_registry_is_the_only_list_of_built_in_detectors():
    assert list(BUILTIN) == list(REGISTRY)
    assert set(saved.SAVED) == {e.name for e in ENTRIES if e.saved}
    assert set(saved._LOADERS) == set(saved.SAVED)  # no codec without an entry
    # every Detector class the package defines is built by an entry
    made = {type(e.make()) for e in ENTRIES}
    for info in pkgutil.iter_modules(detection_package.__path__):
        module = importlib.import_module(f"brake_sim_ros.detection.{info.name}")
        for _, cls in inspect.getmembers(module, inspect.isclass):
            mine = cls.__module__ == module.__name__ and not inspect.isabstract(cls)
            if mine and issubclass(cls, Detector):
                assert cls in made, cls


def test_the_help_names_the_user_forms():
    assert "path/to/file.py:Class" in help_text() and "module:Class" in help_text()
    assert "module:Class" not in help_text(user=False)
