"""Regenerate every documented number and figure from the commands that produce them.

Run from anywhere:

    python docs/generate.py                  # every block and figure (the slow ones too: many minutes)
    python docs/generate.py --fast           # only the blocks and figures that take seconds
    python docs/generate.py ID [ID ...]      # only these
    python docs/generate.py --check [ID ...] # re-run, compare with the pages, write nothing (exit 1 on a difference)

A documented number lives in a *generated block* of a page (README.md or docs/**/*.md):

    <!-- generated: ID -->
    ...the output of BLOCKS[ID].command, as BLOCKS[ID].keep formats it...
    <!-- end generated -->

The same ID may appear on several pages. A block is *checked* (``--check`` compares it with what its command prints
now) unless it is *measured*: wall times and speeds depend on the machine and the moment, so measured blocks are
regenerated but never compared. ``--check`` without IDs covers the fast, checked blocks; ``--slow`` adds the slow
ones. Every command runs this checkout's code (``src/`` first on ``PYTHONPATH``).

``--check`` also reads the prose of every page that has a generated block: a number with a unit outside generated
blocks, code and ``<!-- prose numbers: REASON -->`` ... ``<!-- end prose numbers -->`` regions is an error, so a
result cannot be documented by hand. Such a region names why its numbers are not generated (a parameter, a
historical measurement). A Wilson interval's confidence level ("Wilson 95 %") is a name, not a result.
"""

from __future__ import annotations

import argparse
import difflib
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BLOCK = re.compile(r"<!-- generated: (?P<id>[\w.-]+) -->\n(?P<body>.*?)<!-- end generated -->\n", re.S)
EXEMPT = re.compile(r"<!-- prose numbers: [^>]*-->.*?<!-- end prose numbers -->", re.S)
CODE = re.compile(r"```.*?```|`[^`\n]*`", re.S)
UNITS = r"mm|µm|um|ms|µs|us|s|min|N|N m|mrad|rad|kg|MB|%|×|x real time|Hz|kHz"
NUMBER_WITH_UNIT = re.compile(rf"(?<!Wilson )(?<![\w.])[−-]?\d+(?:[.,]\d+)?\s?(?:{UNITS})(?![\w])")

#: Machine-dependent fragments of the commands' outputs, left out of checked blocks.
TIMING = (
    re.compile(r"^\s*planner: .* per finger per sample.*\n", re.M),
    re.compile(r"^\s*wall time.*\n", re.M),
)
TIMING_FRAGMENTS = (re.compile(r"[,;] planned in [\d.]+ s"), re.compile(r" \(planned in [\d.]+ s\)"),
                    re.compile(r"; control step median: [\d.]+ us"))


def without_timing(text: str) -> str:
    """``text`` less its wall times (lines and fragments)."""
    for line in TIMING:
        text = line.sub("", text)
    for fragment in TIMING_FRAGMENTS:
        text = fragment.sub("", text)
    return text.replace(f"{ROOT}{os.sep}", "")


def console(command: str, text: str) -> str:
    """A console block: the command and its output (wall times left out)."""
    body = without_timing(text).rstrip("\n")
    return f"```console\n$ {command}\n{body}\n```\n"


def as_printed(command: str, text: str) -> str:
    """A console block with the output as printed, timings included."""
    return f"```console\n$ {command}\n{text.rstrip()}\n```\n"


def lines(*patterns: str) -> Callable[[str, str], str]:
    """A console block of the output's lines that match any of ``patterns`` (regexes; the first line, the
    command's heading, always)."""
    compiled = [re.compile(p) for p in patterns]

    def keep(command: str, text: str) -> str:
        out = without_timing(text).splitlines()
        kept = out[:1] + [line for line in out[1:] if any(p.search(line) for p in compiled)]
        return console(command, "\n".join(kept) + "\n")

    return keep


def after(pattern: str) -> Callable[[str, str], str]:
    """A console block of the output's first line (the command's heading) and its lines from the first that matches
    ``pattern`` (a regex) on."""
    compiled = re.compile(pattern)

    def keep(command: str, text: str) -> str:
        out = without_timing(text).splitlines()
        start = next((i for i, line in enumerate(out) if i and compiled.search(line)), len(out))
        return console(command, "\n".join(out[:1] + out[start:]) + "\n")

    return keep


def stripped(*patterns: str) -> Callable[[str, str], str]:
    """A console block of the output less what ``patterns`` (regexes, per line) match: a timing column."""
    compiled = [re.compile(p, re.M) for p in patterns]

    def keep(command: str, text: str) -> str:
        for p in compiled:
            text = p.sub("", text)
        return console(command, text)

    return keep


@dataclass(frozen=True)
class Block:
    """A command whose output is documented, and/or whose figures are.

    ``command`` runs from the repository's root; ``regrasp`` and ``python`` mean this checkout's. ``{out}`` in it is
    a fresh directory, from which ``figures`` (produced name -> path under the root) are copied.
    """

    command: str
    keep: Callable[[str, str], str] | None = console
    slow: bool = False
    measured: bool = False
    status: tuple[int, ...] = (0,)
    figures: dict[str, str] = field(default_factory=dict)


T1, T2 = "examples/scenarios/paper_trajectory_1.toml", "examples/scenarios/paper_trajectory_2.toml"
T3 = "examples/scenarios/paper_trajectory_2_three_fingers.toml"
UP = "examples/scenarios/paper_trajectory_2_gravity_up.toml"
F4, F5 = "examples/scenarios/four_fingers.toml", "examples/scenarios/five_fingers.toml"
DISC, BOX = "examples/scenarios/disc.toml", "examples/scenarios/rounded_box.toml"
#: The lines of a curved scenario's rollout that the README shows: the result, the tracking error and the margins.
CURVE_LINES = (r"^\s+result:", r"^\s+object error", r"^\s+smallest")
STUDY = f"regrasp study {T3} --runs 200 --periods 2 --workers 2 --seed 1 --plot {{out}}"
STUDY_FIGURES = {n: n for n in ("study_success.png", "study_failure_times.png", "study_margins.png", "study.json")}
ROBUSTNESS = {k: f"docs/images/robustness/{v}" for k, v in STUDY_FIGURES.items()}


def _under(folder: str, names: Iterable[str]) -> dict[str, str]:
    return {n: f"docs/images/{folder}/{n}" for n in names}


PLANNER_FIGURES = ("d.png", "feasible.png", "reachable.png")
SUITE_FIGURES = ("suite_outcomes.png", "suite_planning.png", "suite_reasons.png", "suite.json")
SECTION_4 = ("fig_4_2_trajectory_1.png", "fig_4_2_trajectory_1_frames.png", "fig_4_3_three_fingers.png",
             "fig_4_4_gravity_up.png", "fig_4_4_gravity_up_frames.png")

#: Every documented output, by the ID its pages use.
BLOCKS: dict[str, Block] = {
    # the defaults the concepts name, from the code
    "defaults": Block("python docs/defaults.py"),
    # the planner (§2): seconds
    "plan-trajectory-1": Block(f"regrasp plan {T1}", status=(1,)),
    "plan-trajectory-2": Block(f"regrasp plan {T2}"),
    "figures-trajectory-1": Block(f"regrasp plan {T1} --plot {{out}}", None, status=(1,),
                                  figures=_under("trajectory_1", PLANNER_FIGURES)),
    "figures-trajectory-2": Block(f"regrasp plan {T2} --plot {{out}}", None,
                                  figures=_under("trajectory_2", PLANNER_FIGURES)),
    # the regrasp schedule (§4, planned): seconds each, the table a few minutes
    "schedule-three-fingers": Block(f"regrasp plan {T3} --regrasp", after(r"regrasp schedule")),
    "schedule-three-fingers-figure": Block(f"regrasp plan {T3} --regrasp --plot {{out}}", None,
                                           figures={"regrasp.png": "docs/images/trajectory_2/regrasp.png"}),
    "schedule-four-fingers": Block(f"regrasp plan {F4} --regrasp", after(r"regrasp schedule")),
    "schedule-five-fingers": Block(f"regrasp plan {F5} --regrasp", after(r"regrasp schedule"), slow=True),
    "simulate-four-fingers": Block(f"regrasp simulate {F4} --periods 2", slow=True),
    "schedule-four-fingers-figure": Block(f"regrasp plan {F4} --regrasp --plot {{out}}", None,
                                          figures={"regrasp.png": "docs/images/four_fingers/regrasp.png"}),
    "schedule-two-fingers": Block(f"regrasp plan {T2} --regrasp", after(r"regrasp schedule"),
                                  status=(1,)),
    "schedule-gravity-up": Block(f"regrasp plan {UP} --regrasp", after(r"regrasp schedule")),
    "schedule-margins": Block("python examples/08_plan_regrasps.py --envelope-margins 1 2 3 4 5 "
                              "--cone-margins 0.1 0.2 0.3 0.5",
                              stripped(r"\s+planning$", r"(?<= N)\s+[\d.]+ s$"), slow=True),
    # sliding (§3): seconds
    "slide-along-edge": Block("python examples/03_slide_along_edge.py"),
    "figure-3-4": Block("python examples/06_figure_3_4.py --out {out}",
                        figures={"figure_3_4.png": "docs/images/figure_3_4.png"}),
    # the tutorials: seconds
    "own-finger": Block("python examples/05_plan_with_your_own_finger.py"),
    "planning-stack": Block("python examples/04_regrasp_rollout.py", stripped(r"^\s+\d+ steps in .*\n")),
    "study-small": Block(f"regrasp study {T3} --runs 8 --periods 1 --seed 1 --workers 2"),
    # rollouts (§4 on the plant)
    "simulate-trajectory-1": Block(f"regrasp simulate {T1}", status=(1,)),
    "simulate-default": Block("regrasp simulate --periods 3"),
    "section-4": Block("python examples/09_paper_section_4.py --periods 3 --plot {out}", slow=True,
                       figures=_under("section_4", SECTION_4)),
    # plants and contact health: minutes
    "plants-mujoco": Block("python examples/10_mujoco_plant.py", slow=True),
    "health-project": Block("regrasp simulate --periods 2"),
    "health-mujoco": Block("regrasp simulate --periods 2 --plant mujoco", slow=True),
    "health-mujoco-1mm": Block("regrasp simulate --periods 2 --plant mujoco --tip-radius 1", slow=True),
    "health-drake": Block("regrasp simulate --periods 2 --plant drake", slow=True),
    "health-drake-1mm": Block("regrasp simulate --periods 2 --plant drake --tip-radius 1", slow=True),
    "health-pad": Block("regrasp simulate --periods 2 --pad-stiffness 1e5 --pad-damping 63.2", slow=True),
    # robustness studies: tens of minutes each
    "robustness": Block(STUDY, slow=True, figures=ROBUSTNESS),
    "robustness-mujoco": Block(f"{STUDY} --plant mujoco", slow=True,
                               figures={k: f"docs/images/robustness_mujoco/{v}" for k, v in STUDY_FIGURES.items()}),
    "robustness-drake": Block(STUDY.replace("--runs 200", "--runs 100") + " --plant drake", slow=True,
                              figures={k: f"docs/images/robustness_drake/{v}" for k, v in STUDY_FIGURES.items()}),
    # task suites (issue 27): the planning times and memory are measured, so the blocks are never compared
    "suite-small": Block("regrasp suite --variants 12 --workers 2 --plot {out}", as_printed, slow=True, measured=True,
                         figures=_under("suite_small", SUITE_FIGURES)),
    "suite": Block("regrasp suite --workers 2 --plot {out}", as_printed, slow=True, measured=True,
                   figures=_under("suite", SUITE_FIGURES)),
    # curved objects (issue 28): minutes each (a curve's force tables)
    "schedule-disc": Block(f"regrasp plan {DISC} --regrasp --plot {{out}}", after(r"regrasp schedule"), slow=True,
                           figures={"regrasp.png": "docs/images/curves/disc_regrasp.png",
                                    "feasible.png": "docs/images/curves/disc_feasible.png"}),
    "schedule-rounded-box": Block(f"regrasp plan {BOX} --regrasp --plot {{out}}", after(r"regrasp schedule"),
                                  slow=True, figures={"regrasp.png": "docs/images/curves/rounded_box_regrasp.png",
                                                      "feasible.png": "docs/images/curves/rounded_box_feasible.png"}),
    "simulate-disc": Block(f"regrasp simulate {DISC} --periods 2 --plot {{out}}", None, slow=True,
                           figures={"regrasp_rollout.png": "docs/images/curves/disc_rollout.png"}),
    "simulate-rounded-box": Block(f"regrasp simulate {BOX} --periods 2 --plot {{out}}", None, slow=True,
                                  figures={"regrasp_rollout.png": "docs/images/curves/rounded_box_rollout.png"}),
    "turn-a-disc": Block("python examples/15_turn_a_disc.py", slow=True),
    "rounded-box-corner": Block("python examples/16_rounded_box_corner.py --plot {out}",
                                stripped(r"^figures: .*\n"), slow=True,
                                figures={"frames.png": "docs/images/curves/rounded_box_frames.png"}),
    "curves": Block("python docs/curves.py", slow=True),
    "curves-model-errors": Block("python docs/curves.py --model-errors", slow=True),
    # speed: measured, never checked
    "benchmarks": Block("python benchmarks/run.py", as_printed, slow=True, measured=True),
    "first-run": Block("python benchmarks/first_run.py", slow=True, measured=True),
    "many-fingers": Block("python benchmarks/bench_many_fingers.py", as_printed, slow=True, measured=True),
    "curves-planning": Block("python benchmarks/bench_curves.py", as_printed, slow=True, measured=True),
}


def pages(root: Path) -> list[Path]:
    """README.md and every page under docs/."""
    return [root / "README.md", *sorted((root / "docs").rglob("*.md"))]


def argv(command: str, out: str) -> list[str]:
    """The command as this checkout runs it."""
    words = shlex.split(command.replace("{out}", out))
    if words[0] == "regrasp":
        return [sys.executable, "-m", "regrasp.cli.main", *words[1:]]
    return [sys.executable, *words[1:]] if words[0] == "python" else words


def run(block_id: str, block: Block, write_figures: bool, cache: dict[str, str]) -> str:
    """Run a block's command (once per command: ``cache``); copy its figures when asked; the text its pages show
    (or "")."""
    shown = block.command.replace(" {out}", " DIR")
    if block.command in cache:
        return block.keep(shown, cache[block.command]) if block.keep is not None else ""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")])),
               MPLBACKEND="Agg")
    with tempfile.TemporaryDirectory() as out:
        print(f"[{block_id}] {shown}", file=sys.stderr, flush=True)
        done = subprocess.run(argv(block.command, out), cwd=ROOT, env=env, capture_output=True, text=True)
        if done.returncode not in block.status:
            raise SystemExit(f"[{block_id}] exit status {done.returncode} (expected {block.status}):\n"
                             f"{done.stdout}\n{done.stderr}")
        if write_figures:
            for produced, dest in block.figures.items():
                (ROOT / dest).parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(Path(out) / produced, ROOT / dest)
    cache[block.command] = done.stdout.replace(out, "DIR")
    return block.keep(shown, cache[block.command]) if block.keep is not None else ""


def found_blocks(root: Path) -> dict[Path, list[re.Match[str]]]:
    """Each page's generated blocks."""
    return {page: list(BLOCK.finditer(page.read_text())) for page in pages(root)}


def prose_numbers(text: str) -> list[str]:
    """Numbers with units in ``text`` outside generated blocks, exempt regions and code."""
    for pattern in (BLOCK, EXEMPT, CODE):
        text = pattern.sub("", text)
    return NUMBER_WITH_UNIT.findall(text)


def problems(root: Path) -> list[str]:
    """Unknown IDs in the pages, and hand-written numbers on pages with generated blocks."""
    found = []
    for page, matches in found_blocks(root).items():
        found += [f"{page}: unknown block {m['id']!r}" for m in matches if m["id"] not in BLOCKS]
        if matches:
            found += [f"{page}: a number outside generated blocks: {n!r}" for n in prose_numbers(page.read_text())]
    return found


def main(args: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ids", nargs="*", help="blocks to regenerate or check (default: all; --check: the fast ones)")
    parser.add_argument("--check", action="store_true",
                        help="compare with the pages, write nothing; exit 1 if any differ")
    parser.add_argument("--fast", action="store_true", help="leave the slow blocks out")
    parser.add_argument("--slow", action="store_true", help="with --check: the slow blocks too")
    parser.add_argument("--no-figures", action="store_true", help="regenerate the blocks only, not the figures")
    parser.add_argument("--root", type=Path, default=ROOT, help="where the pages are (default: this checkout)")
    a = parser.parse_args(args)
    unknown = [i for i in a.ids if i not in BLOCKS]
    if unknown:
        parser.error(f"unknown block(s) {', '.join(unknown)}; known: {', '.join(BLOCKS)}")
    ids = a.ids or [i for i, b in BLOCKS.items() if not (b.slow and (a.fast or (a.check and not a.slow)))
                    and not (a.check and (b.measured or b.keep is None))]
    failures = problems(a.root) if a.check else []
    cache: dict[str, str] = {}
    outputs = {i: run(i, BLOCKS[i], not (a.check or a.no_figures), cache) for i in ids}
    pages_blocks = found_blocks(a.root)
    for i, text in outputs.items():
        if BLOCKS[i].keep is not None and not any(m["id"] == i for ms in pages_blocks.values() for m in ms):
            failures.append(f"block {i!r} is on no page")
    for page, matches in pages_blocks.items():
        source = page.read_text()
        updated = source
        for m in reversed(matches):
            if m["id"] not in outputs or BLOCKS[m["id"]].keep is None:
                continue
            new = outputs[m["id"]]
            if a.check and not BLOCKS[m["id"]].measured and m["body"] != new:
                diff = difflib.unified_diff(m["body"].splitlines(), new.splitlines(), "page", "command", lineterm="")
                failures.append(f"{page}: block {m['id']!r} differs from its command's output:\n" + "\n".join(diff))
            updated = updated[:m.start("body")] + new + updated[m.end("body"):]
        if not a.check and updated != source:
            page.write_text(updated)
            print(f"updated {page.relative_to(a.root)}", file=sys.stderr)
    for f in failures:
        print(f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
