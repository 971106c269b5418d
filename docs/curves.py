"""Print the curved objects' rollouts as one table (blocks of ``docs/generate.py``): each row one
``regrasp simulate SCENARIO --periods 2 --json [--plant mujoco] [--plant-mass-scale S] [--plant-mu-scale S]`` run as
a user runs it, in a subprocess, two at a time.

Run: python docs/curves.py [--model-errors]
Without options: the disc and the rounded box on the project plant, on MuJoCo and on Drake. With
``--model-errors``: both on the project plant whose object is 10 % lighter or heavier, or whose friction is 10 % lower
or higher, than the model the hand plans and controls with.
"""

import argparse
import json
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("disc", "rounded_box")


def simulate(scenario: str, extra: tuple[str, ...]) -> dict:
    """The ``--json`` document of one ``regrasp simulate`` run."""
    command = [sys.executable, "-m", "regrasp.cli.main", "simulate", f"examples/scenarios/{scenario}.toml",
               "--periods", "2", "--json", *extra]
    proc = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=False)
    if proc.returncode not in (0, 1) or not proc.stdout.strip():
        raise SystemExit(f"{' '.join(command)} failed ({proc.returncode}):\n{proc.stderr}")
    return json.loads(proc.stdout)


def row(scenario: str, plant: str, doc: dict) -> str:
    """One table row: the outcome, the tracking error after the transient, the margins and the least force a contact
    carried while held."""
    failure = doc["failure"]
    outcome = "SUCCESS" if doc["success"] else f"{failure['kind']} at {failure['time']:.2f} s"
    least = min(h["least_held_force"] for h in doc["contact_health"] if h["least_held_force"] is not None)
    err, rot = doc["max_object_error_after_transient"], doc["max_orientation_error_after_transient"]
    slides = sum(doc["regrasps"].values())
    return (f"{scenario:12s} {plant:22s} {outcome:9s} {err * 1e3:8.4f} mm {rot * 1e3:7.3f} mrad "
            f"{doc['min_envelope_margin'] * 1e3:6.2f} mm {doc['min_cone_margin']:6.3f} N {least:6.3f} N "
            f"{slides:6d} {doc['replans']:8d}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--model-errors", action="store_true",
                        help="the project plant 10 %% off the model in mass or friction, instead of the three plants")
    args = parser.parse_args()
    if args.model_errors:
        plants = {f"project, {what} x {s:g}": ("--plant-mass-scale" if what == "mass" else "--plant-mu-scale", f"{s:g}")
                  for what in ("mass", "mu") for s in (0.9, 1.1)}
    else:
        plants = {"project": (), "mujoco": ("--plant", "mujoco"), "drake": ("--plant", "drake")}
    runs = [(scenario, plant, extra) for scenario in SCENARIOS for plant, extra in plants.items()]
    with ThreadPoolExecutor(2) as pool:
        docs = list(pool.map(lambda r: simulate(r[0], r[2]), runs))
    print(f"{'scenario':12s} {'plant':22s} {'result':9s} {'object error':>11s} {'orientation':>12s} "
          f"{'envelope':>9s} {'cone':>8s} {'least held':>10s} {'slides':>6s} {'re-plans':>8s}")
    for (scenario, plant, _), doc in zip(runs, docs):
        print(row(scenario, plant, doc))
    print("(two periods each; the errors after the first 0.5 s; the margins the smallest over the run: the envelope's "
          "of any contact, the cone's of a held one; least held: the least normal force a held contact carried)")


if __name__ == "__main__":
    main()
