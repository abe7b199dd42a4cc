"""The documentation's references hold: every file under docs/ that the README, the docs,
the code and the tests cite exists (and every design.md#anchor they cite is a heading there),
every image a Markdown file shows is there, CI runs the README's test command, neither the
docs nor the code, kernels and tests name tracker issues, and the generated command-line
reference lists every option of the parser."""

import argparse
import importlib.util
import re
import sys
import types
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
#: A docs/ file named in prose or code: docs/<name>.md, docs/<sub>/<name>.png, docs/design.md#<anchor>.
CITED = re.compile(r"docs/([\w./\-]+\.(?:md|png))(?:#([\w\-]+))?")
#: An image shown in Markdown, ![alt](path), or in HTML, <img src="path">.
SHOWN = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)|<img\s[^>]*src=\"([^\"]+)\"")
#: A tracker item named in prose: "issue N", "issues N and M", "issue #N".
TRACKER = re.compile(r"\bissues? #?\d+\b", re.IGNORECASE)
#: Pages removed when their content moved into the site (design.md, benchmarks.md, gallery.md).
RETIRED = {"choices.md", "performance.md"}
#: Written by the docs build from the code (docs/_ext/cli_reference.py), not kept in git.
GENERATED = {DOCS / "reference" / "cli.md", DOCS / "reference" / "options.md"}


def _markdown() -> list[Path]:
    """README and every Markdown page of the docs, the build output left out."""
    return [ROOT / "README.md",
            *sorted(p for p in DOCS.rglob("*.md") if "_build" not in p.parts and p not in GENERATED)]


def _code() -> list[Path]:
    """The package, the tools and the tests."""
    return [*sorted((ROOT / "clsolid").rglob("*.py")), *sorted((ROOT / "tools").glob("*.py")),
            *sorted((ROOT / "tests").rglob("*.py"))]


def _docs_text() -> list[Path]:
    """Every text file under docs/ (pages, configuration, extensions) and the README."""
    return [*_markdown(), *sorted(p for p in DOCS.rglob("*.py") if "_build" not in p.parts)]


def _slug(heading: str) -> str:
    """GitHub's (and MyST's) anchor for a heading: lower case, punctuation dropped, spaces to '-'."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    text = re.sub(r"```.*?```", "", page.read_text(encoding="utf-8"), flags=re.DOTALL)
    return {_slug(m.group(1)) for m in re.finditer(r"^#{1,6}\s+(.+?)\s*$", text, re.MULTILINE)}


def _broken(paths: list[Path], skip: set[str] = frozenset()) -> set[str]:
    broken = set()
    for path in paths:
        for page, anchor in CITED.findall(path.read_text(encoding="utf-8")):
            if page in skip:
                continue
            target = DOCS / page
            where = f"{path.relative_to(ROOT)}: docs/{page}{'#' + anchor if anchor else ''}"
            if not target.is_file():
                broken.add(where)
            elif anchor and target.suffix == ".md" and anchor not in _anchors(target):
                broken.add(where + " (no such heading)")
    return broken


def test_every_docs_file_and_anchor_the_documentation_cites_exists():
    broken = _broken(_markdown())
    assert not broken, sorted(broken)


def test_every_docs_file_and_anchor_the_code_and_tests_cite_exists():
    broken = _broken(_code(), skip=RETIRED)
    assert not broken, sorted(broken)


def test_the_code_cites_no_retired_page():
    cited = {f"{path.relative_to(ROOT)}: docs/{page}" for path in _code()
             for page, _ in CITED.findall(path.read_text(encoding="utf-8")) if page in RETIRED}
    assert not cited, sorted(cited)


def test_every_image_shown_exists():
    missing = {f"{path.relative_to(ROOT)}: {ref}" for path in _markdown()
               for match in SHOWN.findall(path.read_text(encoding="utf-8")) for ref in match
               if ref and not (path.parent / ref).is_file()}
    assert not missing, sorted(missing)


def test_the_patterns_find_what_the_readme_cites():
    """The patterns above would not silently match nothing."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert {"getting-started.md", "design.md", "gallery.md"} <= {page for page, _ in CITED.findall(readme)}
    assert [ref for match in SHOWN.findall(readme) for ref in match if ref]
    assert _slug("Chen-Wang weights") == "chen-wang-weights" and _slug("## `clsolid synth`"[3:]) == "clsolid-synth"


def test_ci_runs_the_readme_test_command_then_the_slow_tests():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    readme = (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
    command = next(line for line in readme if line.endswith("python -m pytest"))
    slow = next(i for i, line in enumerate(ci) if line.startswith("python -m pytest -m slow"))
    assert command in ci and ci.index(command) < slow


#: Where no tracker item may be named, each with the files read there.
TRACKED = {
    "docs": _docs_text,
    "clsolid": lambda: sorted(p for p in (ROOT / "clsolid").rglob("*") if p.suffix in (".py", ".toml")),
    "kernels": lambda: sorted((ROOT / "kernels").rglob("*.cl")),
    "tests": lambda: sorted((ROOT / "tests").rglob("*.py")),
}


def test_the_tracker_pattern_finds_issue_numbers():
    # written so that this file names no tracker item itself
    assert TRACKER.search(f"as issue {10} asks") and TRACKER.search(f"Issue #{12}") and TRACKER.search(f"issues {10}")
    assert not TRACKER.search("not an issue target")


@pytest.mark.parametrize("tree", sorted(TRACKED))
def test_no_tracker_issue_is_named(tree):
    """The docs (README included), the code, the kernels and the tests say what a thing does,
    not which tracker item asked for it."""
    paths = TRACKED[tree]()
    assert paths
    found = {f"{path.relative_to(ROOT)}:{text.count(chr(10), 0, m.start()) + 1}: {m.group(0)}"
             for path in paths for text in [path.read_text(encoding="utf-8")]
             for m in TRACKER.finditer(text)}
    assert not found, sorted(found)


def test_the_docs_cite_the_sources_not_the_spec_notes():
    found = {str(path.relative_to(ROOT)) for path in _docs_text()
             if "thesis_spec" in path.read_text(encoding="utf-8")}
    assert not found, sorted(found)


def _cli_reference():
    spec = importlib.util.spec_from_file_location("cli_reference", DOCS / "_ext" / "cli_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_cli_reference_lists_every_option_of_every_subcommand():
    ref = _cli_reference()
    from clsolid.cli import build_parser

    parser = ref.load_parser("clsolid.cli:build_parser")
    page = ref.render(parser)
    subs = ref.subcommands(parser)
    assert {name for name, _, _ in subs} >= {"synth", "devices", "evaluate"}
    for name, sub, _ in subs:
        assert f"## `clsolid {name}`" in page
        for action in sub._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help") and action.help is not argparse.SUPPRESS:
                    assert f"`{flag}" in page, (name, flag)
    assert build_parser().prog == parser.prog


def test_the_cli_reference_follows_the_parser_groups_and_asks_for_hidden_ones():
    """A parser with named groups, some hidden unless show_all=True, comes out group by group."""
    ref = _cli_reference()

    def factory(show_all: bool = False) -> argparse.ArgumentParser:
        parser = argparse.ArgumentParser(prog="tool", description="A tool.")
        sub = parser.add_subparsers(dest="command")
        run = sub.add_parser("run", help="run it", description="Run the tool.")
        run.add_argument("source", help="what to read")
        main = run.add_argument_group("Main options", "What most runs need.")
        main.add_argument("--size", type=int, default=64, metavar="N", help="side (default %(default)s)")
        main.add_argument("--mode", choices=("a", "b"), default="a", help="how")
        advanced = run.add_argument_group("OpenCL tuning")
        advanced.add_argument("--width", type=int, default=16,
                              help="vector width_x *raw* [0-1] $x$" if show_all else argparse.SUPPRESS)
        return parser

    module = types.ModuleType("_toy_cli")
    module.factory = factory
    sys.modules["_toy_cli"] = module
    try:
        page = ref.render(ref.load_parser("_toy_cli:factory"))
    finally:
        del sys.modules["_toy_cli"]
    assert page.index("## `tool run`") < page.index("### Main options") < page.index("### OpenCL tuning")
    assert "What most runs need." in page and "Run the tool." in page
    assert "- `--size N`: side (default 64)." in page
    assert "- `--mode {a,b}`: how. Default: `a`." in page
    assert r"- `--width WIDTH`: vector width\_x \*raw\* \[0-1\] \$x\$. Default: `16`." in page
    assert "- `source`: what to read." in page
