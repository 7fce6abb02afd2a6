"""The site's front page and the package's descriptions, current: the install line is the
README's main command, the opening and every description speak of four-bar and hinge lids,
and the guide table links every page of the site's navigation."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
INDEX = (ROOT / "docs" / "index.md").read_text()
README = (ROOT / "README.md").read_text()


def _first_block_after(text: str, marker: str) -> str:
    m = re.search(re.escape(marker) + r".*?```[a-z]*\n(.*?)```", text, re.S)
    assert m, f"no code block after {marker}"
    return m.group(1).strip()


def _nav_pages() -> list[str]:
    """The pages of mkdocs.yml's nav (each ``- Title: page`` line below ``nav:``)."""
    nav = (ROOT / "mkdocs.yml").read_text().split("\nnav:\n", 1)[1]
    return re.findall(r"^\s+- [^:\n]+:\s+(\S+\.(?:md|ipynb))\s*$", nav, re.M)


def _guide_table() -> str:
    table = INDEX.split("## The guide", 1)[1]
    return "\n".join(line for line in table.splitlines() if line.startswith("|"))


def test_the_install_line_is_the_readmes_main_command():
    readme = _first_block_after(README, "<!-- main-command -->")
    assert "softclose prepare --robust" in readme
    assert _first_block_after(INDEX, "## Install and run") == readme


def test_the_guide_table_links_every_page_of_the_navigation():
    pages = _nav_pages()
    assert "report.md" in pages and "api.md" in pages and len(pages) > 20, pages
    table = _guide_table()
    missing = [p for p in pages if p != "index.md" and f"]({p})" not in table]
    assert missing == [], f"pages of mkdocs.yml's nav not in the front page's guide: {missing}"


def test_the_front_page_names_what_softclose_designs():
    opening = INDEX.split("## Install and run", 1)[0].lower()
    assert "four-bar" in opening and "hinge" in opening
    table = _guide_table().lower()
    for what in ("temperature", "gas strut", "made to order", "hinge", "sign-off report"):
        assert what in table, what


def test_the_descriptions_speak_of_four_bar_and_hinge_lids():
    pyproject = (ROOT / "pyproject.toml").read_text()
    description = re.search(r'^description = "(.*)"$', pyproject, re.M).group(1)
    out = subprocess.run([sys.executable, "-m", "softclose", "--help"], capture_output=True,
                         text=True, check=True).stdout
    first = out.split("\n\n")[1]             # the paragraph after the usage line
    readme = README.split("\n\n")[1]
    for text in (description, " ".join(first.split()), readme):
        assert "four-bar" in text and "hinge" in text, text
