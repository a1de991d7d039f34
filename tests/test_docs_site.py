"""The documentation builds as a site with MkDocs in strict mode: a link to a page or an anchor that is not there fails.

Skips, saying how to install it, where mkdocs is missing (it is in the test extra: ``pip install -e .[test]``).
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
pytest.importorskip("mkdocs", reason="mkdocs is in the test extra: pip install -e .[test]")


def build(root: Path, site: Path) -> subprocess.CompletedProcess:
    """``mkdocs build --strict`` of the project at ``root`` into ``site`` (never into the repository)."""
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f", str(root / "mkdocs.yml"),
                           "-d", str(site)], capture_output=True, text=True, timeout=240)


def copy_of_the_docs(tmp_path: Path) -> Path:
    shutil.copytree(ROOT / "docs", tmp_path / "docs")
    shutil.copy(ROOT / "mkdocs.yml", tmp_path / "mkdocs.yml")
    return tmp_path


def test_the_docs_build_in_strict_mode(tmp_path):
    done = build(ROOT, tmp_path / "site")
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "site" / "verification" / "time.html").is_file()
    assert (tmp_path / "site" / "live.html").is_file() and (tmp_path / "site" / "images").is_dir()


def test_a_broken_link_fails_the_build_and_names_the_page_and_the_link(tmp_path):
    root = copy_of_the_docs(tmp_path / "copy")
    page = root / "docs" / "pictures.md"
    page.write_text(page.read_text() + "\nSee [the gone chapter](verification/gone.md).\n")
    done = build(root, tmp_path / "site")
    assert done.returncode != 0
    assert "pictures.md" in done.stderr and "verification/gone.md" in done.stderr


def test_a_missing_anchor_fails_the_build(tmp_path):
    root = copy_of_the_docs(tmp_path / "copy")
    page = root / "docs" / "live.md"
    page.write_text(page.read_text() + "\nSee [its tests](#no-such-heading).\n")
    done = build(root, tmp_path / "site")
    assert done.returncode != 0 and "#no-such-heading" in done.stderr


def test_a_page_not_in_the_menu_still_builds_and_its_links_are_checked(tmp_path):
    """Pages are added to the menu by hand (mkdocs.yml says how): until then they build, broken links still fail."""
    root = copy_of_the_docs(tmp_path / "copy")
    (root / "docs" / "newpage.md").write_text("# New\n\nSee [the live page](live.md).\n")
    assert build(root, tmp_path / "site").returncode == 0
    (root / "docs" / "newpage.md").write_text("# New\n\nSee [nothing](nothing.md).\n")
    done = build(root, tmp_path / "site2")
    assert done.returncode != 0 and "nothing.md" in done.stderr


def test_every_chapter_of_verification_is_in_its_index_and_in_the_menu():
    chapters = sorted(p.name for p in (ROOT / "docs" / "verification").glob("*.md"))
    index = (ROOT / "docs" / "verification.md").read_text()
    menu = (ROOT / "mkdocs.yml").read_text()
    assert len(chapters) >= 10
    for name in chapters:
        assert f"](verification/{name})" in index and f": verification/{name}" in menu, name
    assert len(index.splitlines()) < 120  # an index, not the 3 000 lines it was


def test_no_doc_names_a_section_of_the_old_single_file():
    """References to docs/verification.md went to the chapter they meant; the index is named only as a whole."""
    named = re.compile(r"verification\.md,\s+\*")
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]:
        assert not named.search(path.read_text()), path


def test_the_code_names_a_chapter_of_verification_not_the_index():
    """Comments, docstrings and help texts that point to the verification docs name the chapter file (the index
    docs/verification.md has no sections left to cite), and every docs/ file the code names exists; the same in
    the comments of the example and DALA's property, observer and campaign files."""
    sources = [p for d in ("genom2bip", "runtime", "bench", "tests") for p in sorted((ROOT / d).rglob("*.py"))
               if p.name != "test_docs_site.py"]
    sources += [p for d in ("examples", "descriptions") for ext in ("*.mcl", "*.yaml", "*.gen")
                for p in sorted((ROOT / d).rglob(ext))]
    assert len(sources) > 100 and ROOT / "examples" / "props.mcl" in sources
    for path in sources:
        text = path.read_text(encoding="utf-8")
        assert "docs/verification.md" not in text, path
        for name in re.findall(r"docs/[A-Za-z0-9_/.-]+?\.md", text):
            assert (ROOT / name).is_file(), (path, name)
