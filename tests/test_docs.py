"""The documentation's references hold: every file under docs/ that the README, the docs and
the code cite exists, every image a Markdown file shows is there, and CI runs the README's
test command."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: A docs/ file named in prose or code: docs/name.md, docs/name.png.
CITED = re.compile(r"docs/[\w.\-]+\.(?:md|png)")
#: An image shown in Markdown: ![alt](path).
SHOWN = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def _texts() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "clsolid").rglob("*.py")),
            *sorted((ROOT / "tools").glob("*.py"))]


def test_every_cited_docs_file_exists():
    missing = {f"{path.relative_to(ROOT)}: {ref}" for path in _texts()
               for ref in CITED.findall(path.read_text(encoding="utf-8")) if not (ROOT / ref).is_file()}
    assert not missing, sorted(missing)


def test_every_image_shown_exists():
    markdown = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    missing = {f"{path.relative_to(ROOT)}: {ref}" for path in markdown
               for ref in SHOWN.findall(path.read_text(encoding="utf-8")) if not (path.parent / ref).is_file()}
    assert not missing, sorted(missing)


def test_the_docs_files_are_found_by_the_pattern():
    """The pattern above would not silently match nothing."""
    assert {"docs/choices.md", "docs/performance.md", "docs/gallery.md"} <= set(
        CITED.findall((ROOT / "README.md").read_text(encoding="utf-8")))


def test_ci_runs_the_readme_test_command():
    command = (ROOT / ".ci" / "run").read_text(encoding="utf-8").strip().splitlines()[-1]
    assert command in (ROOT / "README.md").read_text(encoding="utf-8")
