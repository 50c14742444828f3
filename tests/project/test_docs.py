"""The README is a front page and the docs are reachable from it: every ``docs/*.md`` page
is linked from README.md, every relative link and anchor in README, docs and bags/README
resolves, the README stays short, and the blocks a command prints
(``scripts/gen_docs.py``) equal what the command prints now."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README_MAX_LINES = 320

_FENCE = re.compile(r"^(```|~~~).*?^\1[^\n]*$", re.S | re.M)
_LINK = re.compile(r"\]\(([^)\s]+)\)")
_HEADING = re.compile(r"^(#{1,6}) +(.+?) *#*$", re.M)


def _gen_docs():
    spec = importlib.util.spec_from_file_location("gen_docs", ROOT / "scripts" / "gen_docs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def slug(heading: str) -> str:
    """GitHub's anchor for a heading: lower case, inline markup and punctuation dropped
    (letters, digits, ``_`` and ``-`` kept), spaces to ``-``."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link's text only
    text = text.lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(text: str) -> set[str]:
    """Every heading anchor of a Markdown page (headings in code blocks are not), with
    GitHub's ``-1``, ``-2`` suffixes for repeats."""
    seen: dict[str, int] = {}
    out = set()
    for m in _HEADING.finditer(_FENCE.sub("", text)):
        s = slug(m.group(2))
        n = seen.get(s, 0)
        seen[s] = n + 1
        out.add(s if n == 0 else f"{s}-{n}")
    return out


def links(text: str) -> list[str]:
    """Link targets of a page, outside code blocks and inline code."""
    prose = _FENCE.sub("", text)
    prose = re.sub(r"`[^`\n]*`(?!\])", "", prose)  # inline code that is not a link's text
    return _LINK.findall(prose)


def broken_links(page: Path) -> list[str]:
    """The relative links of ``page`` whose file or heading anchor does not exist."""
    bad = []
    text = page.read_text(encoding="utf-8")
    for target in links(text):
        if re.match(r"[a-z][a-z0-9+.-]*:", target):  # https:, mailto:, ...
            continue
        path, _, anchor = target.partition("#")
        dest = (page.parent / path).resolve() if path else page
        if not dest.exists():
            bad.append(f"{page.name}: {target}: no such file")
        elif (
            anchor
            and dest.suffix == ".md"
            and anchor not in anchors(dest.read_text(encoding="utf-8"))
        ):
            bad.append(f"{page.name}: {target}: no such heading in {dest.name}")
    return bad


def unlinked_pages(readme: Path, docs: Path) -> list[str]:
    """``docs/*.md`` pages the README does not link to."""
    linked = {
        (readme.parent / t.partition("#")[0]).resolve()
        for t in links(readme.read_text(encoding="utf-8"))
        if t.partition("#")[0]
    }
    return sorted(p.name for p in docs.glob("*.md") if p.resolve() not in linked)


def _pages() -> list[Path]:
    return [ROOT / "README.md", ROOT / "bags" / "README.md", *sorted(ROOT.glob("docs/*.md"))]


def test_every_docs_page_is_linked_from_the_readme():
    assert unlinked_pages(ROOT / "README.md", ROOT / "docs") == []


@pytest.mark.parametrize("page", _pages(), ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_and_anchors_resolve(page):
    assert broken_links(page) == []


def test_readme_is_a_front_page():
    lines = (ROOT / "README.md").read_text(encoding="utf-8").count("\n")
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines: move sections to docs/"


def test_readme_keeps_the_test_command_ci_runs():
    """``.ci/run`` runs exactly the README's test command."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    command = (
        "bash scripts/setup.sh && .venv/bin/ruff check brake_sim_ros tests"
        " && .venv/bin/python -m pytest -q"
    )
    assert command in readme
    for part in command.split(" && "):
        assert part in ci


def test_the_checks_fail_on_an_unlinked_page_and_a_broken_link(tmp_path):
    docs = tmp_path / "docs"
    docs.mkdir()
    (docs / "a.md").write_text("# A page\n\n## Its part\n\n[back](../README.md)\n")
    (docs / "b.md").write_text("# B\n\n[a part](a.md#its-part) [gone](a.md#no-part) [x](c.md)\n")
    readme = tmp_path / "README.md"
    readme.write_text("# R\n\n[A](docs/a.md#its-part)\n\n```\n[B](docs/b.md)\n```\n")
    assert unlinked_pages(readme, docs) == ["b.md"]  # a link inside a code block is no link
    assert broken_links(docs / "a.md") == []
    assert broken_links(docs / "b.md") == [
        "b.md: a.md#no-part: no such heading in a.md",
        "b.md: c.md: no such file",
    ]


def test_slugs_follow_github():
    assert slug("Topics") == "topics"
    assert slug("Live monitoring: `brake-sim monitor`") == "live-monitoring-brake-sim-monitor"
    assert slug("Scores on the reference campaign's test split") == (
        "scores-on-the-reference-campaigns-test-split"
    )
    assert anchors("# A\n## B\n## B\n```\n## C\n```\n") == {"a", "b", "b-1"}


def test_generated_blocks_equal_what_their_commands_print():
    """Every cheap generated block is what its command prints now (``brake-sim validate``
    takes minutes: ``scripts/gen_docs.py --all`` reruns it)."""
    gen = _gen_docs()
    found = {
        (page.name, name): body
        for page in gen.pages()
        for name, body in gen.blocks(page.read_text(encoding="utf-8"))
    }
    names = {name for _, name in found}
    assert {
        "brake-sim defects",
        "brake-sim scenarios",
        "catalogue table",
        "benchmark list",
        "campaign table",
    } <= names
    fresh = gen.fresh_outputs(names, include_expensive=False)
    stale = [
        f"{page}: {name}"
        for (page, name), body in found.items()
        if name in fresh and body != fresh[name]
    ]
    assert stale == [], "run: PYTHONPATH=. .venv/bin/python scripts/gen_docs.py"


def test_an_unknown_generated_block_is_refused():
    gen = _gen_docs()
    with pytest.raises(ValueError, match="unknown"):
        gen.source("ls -l")
    text = (
        "x\n<!-- generated by scripts/gen_docs.py: catalogue table -->\nold\n"
        "<!-- end generated -->\n"
    )
    assert gen.render(text, {"catalogue table": "new\n"}).split("\n")[2] == "new"
