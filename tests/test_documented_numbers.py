"""Every number a command prints on a documentation page (README.md, docs/**/*.md) is the command's: the pages'
generated blocks equal what ``docs/generate.py`` makes of their commands' outputs now, an edited number fails the
check, and no result is written by hand outside a generated block."""

import importlib.util
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("docs_generate", ROOT / "docs" / "generate.py")
generate = importlib.util.module_from_spec(_spec)
sys.modules["docs_generate"] = generate
_spec.loader.exec_module(generate)

#: Fast, deterministic blocks the slow tests re-run for real (seconds each).
FAST = ["defaults", "plan-trajectory-1", "simulate-trajectory-1", "schedule-two-fingers"]


def page_with(block_id: str) -> Path:
    """The first page that shows ``block_id``."""
    return next(p for p, ms in generate.found_blocks(ROOT).items() if any(m["id"] == block_id for m in ms))


def edit_a_number(text: str, block_id: str) -> str:
    """``text`` with the last digit of the first decimal number in ``block_id``'s output changed."""
    m = next(m for m in generate.BLOCK.finditer(text) if m["id"] == block_id)
    body_start = m.start("body") + m["body"].index("\n", m["body"].index("$ ")) + 1   # after the command's line
    number = re.compile(r"\d+\.(\d+)").search(text, body_start, m.end("body"))
    assert number is not None, f"no decimal number in block {block_id!r}"
    i = number.end() - 1
    return text[:i] + str((int(text[i]) + 1) % 10) + text[i + 1:]


def copy_pages(tmp_path: Path) -> Path:
    """README.md and docs/ copied under ``tmp_path`` (the pages ``--root`` reads)."""
    shutil.copyfile(ROOT / "README.md", tmp_path / "README.md")
    shutil.copytree(ROOT / "docs", tmp_path / "docs", ignore=shutil.ignore_patterns("images", "*.py"))
    return tmp_path


def test_every_block_on_a_page_is_registered_and_every_registered_text_on_a_page():
    shown = {m["id"] for ms in generate.found_blocks(ROOT).values() for m in ms}
    assert shown - set(generate.BLOCKS) == set()
    assert {i for i, b in generate.BLOCKS.items() if b.keep is not None} - shown == set()


def test_the_fast_blocks_are_registered_checked_and_fast():
    for i in FAST:
        assert not generate.BLOCKS[i].slow and not generate.BLOCKS[i].measured, i


def test_no_hand_written_numbers_on_generated_pages():
    assert generate.problems(ROOT) == []


def test_a_hand_written_number_is_found(tmp_path):
    root = copy_pages(tmp_path)
    page = root / page_with("plan-trajectory-1").relative_to(ROOT)
    page.write_text(page.read_text() + "\nThe planner keeps 4.98 mm of margin.\n")
    assert any("4.98 mm" in p for p in generate.problems(root))


def test_check_compares_each_block_with_its_command(tmp_path, monkeypatch, capsys):
    """The comparison alone, with the command's output taken from the page: equal passes, an edit fails."""
    root = copy_pages(tmp_path)
    page = root / page_with("plan-trajectory-1").relative_to(ROOT)
    body = next(m["body"] for m in generate.BLOCK.finditer(page.read_text()) if m["id"] == "plan-trajectory-1")
    monkeypatch.setattr(generate, "run", lambda block_id, block, write, cache: body)
    assert generate.main(["--check", "plan-trajectory-1", "--root", str(root)]) == 0
    page.write_text(edit_a_number(page.read_text(), "plan-trajectory-1"))
    assert generate.main(["--check", "plan-trajectory-1", "--root", str(root)]) == 1
    assert "block 'plan-trajectory-1' differs" in capsys.readouterr().err


def check(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "docs" / "generate.py"), "--check", *args],
                          capture_output=True, text=True, check=False)


@pytest.mark.slow
def test_the_fast_blocks_equal_their_commands_output_now():
    proc = check(*FAST)
    assert proc.returncode == 0, proc.stdout + proc.stderr


@pytest.mark.slow
def test_an_edited_number_fails_the_check(tmp_path):
    root = copy_pages(tmp_path)
    page = root / page_with("plan-trajectory-1").relative_to(ROOT)
    page.write_text(edit_a_number(page.read_text(), "plan-trajectory-1"))
    proc = check("plan-trajectory-1", "--root", str(root))
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "block 'plan-trajectory-1' differs from its command's output" in proc.stderr
