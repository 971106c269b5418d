"""The documentation site builds without a warning (``mkdocs build --strict``: broken links and anchors, pages
left out of the navigation, docstrings griffe cannot parse), every page is in the navigation, and the README opens
with the two commands and stays short."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]


def nav_pages(nav: list) -> set[str]:
    """Every page the ``nav`` of mkdocs.yml lists."""
    found = set()
    for item in nav:
        for value in (item.values() if isinstance(item, dict) else [item]):
            found |= nav_pages(value) if isinstance(value, list) else {value}
    return found


def test_every_page_is_in_the_navigation():
    config = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    pages = {str(p.relative_to(ROOT / "docs")) for p in (ROOT / "docs").rglob("*.md")}
    assert pages - nav_pages(config["nav"]) == set()
    assert nav_pages(config["nav"]) - pages == set()


def test_the_readme_opens_with_the_two_commands_and_is_short():
    lines = (ROOT / "README.md").read_text().splitlines()
    assert lines[2:6] == ["```bash", "pip install -e . && regrasp simulate --periods 3 --rrd rollout.rrd",
                          "pip install -e '.[test]' && python -m pytest -q -n 2", "```"]
    assert len(lines) <= 200


@pytest.mark.slow
def test_the_site_builds_strictly(tmp_path):
    mkdocs = shutil.which("mkdocs")
    command = [mkdocs] if mkdocs else [sys.executable, "-m", "mkdocs"]
    proc = subprocess.run([*command, "build", "--strict", "--site-dir", str(tmp_path / "site")], cwd=ROOT,
                          capture_output=True, text=True, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "api" / "core" / "index.html").is_file()
