"""Set-up shared by the benchmark scripts (run as ``python benchmarks/<script>.py``)."""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from regrasp import Grasp, Hand, Plant, PlantContact, ReducedModel, load_scenario

ROOT = Path(__file__).resolve().parents[1]


def child_json(script: str, *args: str) -> dict:
    """Run ``python SCRIPT --child *ARGS`` in a fresh process (its own imports, compiles and memory); the JSON document
    on the last line of its stdout."""
    done = subprocess.run([sys.executable, script, "--child", *args], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def median_us(fn, n: int) -> float:
    """Median wall time [µs] of ``n`` calls of ``fn`` (after one warm-up call)."""
    fn()
    samples = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return float(np.median(samples) * 1e6)


@dataclass
class SlidingHold:
    """The paper's hand holding the rectangle still while finger 1 slides up at 5 mm/s."""

    scenario: object
    hand: Hand
    model: ReducedModel
    S: np.ndarray
    S_dot: np.ndarray
    state: object
    tau: np.ndarray
    plant: Plant
    plant_reference: Plant

    def plant_step(self, plant: Plant | None = None) -> None:
        """One step of ``plant`` (default: the compiled one), restarting from the initial state every 50 ms."""
        plant = self.plant if plant is None else plant
        if plant.state is None or plant.state.t > 0.05:
            plant.reset(self.state.q, self.state.q_dot, self.S[:3], self.S_dot[:3])
        plant.step(self.tau)


def sliding_hold() -> SlidingHold:
    sc = load_scenario(ROOT / "examples" / "scenarios" / "paper_trajectory_2.toml")
    hand = Hand([c.finger for c in sc.contacts], gravity_in_hand=sc.gravity_in_hand)
    model = ReducedModel(hand, Grasp(sc.polygon, [1, 3], ["sliding", "fixed"]), xi=[0.0, 0.0])
    S, S_dot = np.array([0.0, 0.12, 0.0, 0.0]), np.array([0.0, 0.0, 0.0, 0.005])
    st = model.state(S, S_dot)
    # torques that keep the object still: contact forces from the object's balance plus a squeeze
    frames = model.grasp.surface_frames(S[:3])
    forces = np.linalg.lstsq(st.G, -model.f_g, rcond=None)[0]
    forces += 2.0 * np.concatenate([frames[0][:, 0], frames[1][:, 0]])
    tau = st.hand.nonlinear + st.hand.jacobian.T @ forces
    plants = [Plant(hand, sc.polygon, [PlantContact(1, "sliding", 0.0, 1.0), PlantContact(3, "fixed", 0.0)],
                    friction=0.0, stop_on=(), compiled=compiled) for compiled in (True, False)]
    for plant in plants:
        plant.reset(st.q, st.q_dot, S[:3], S_dot[:3])
    return SlidingHold(sc, hand, model, S, S_dot, st, tau, *plants)


def parse_args(doc: str, full: int) -> tuple[argparse.Namespace, int]:
    """``--quick`` / ``--json`` of a benchmark script (``doc``: its docstring), and the number of timed
    calls per item: ``full``, or 20 for the CI smoke run."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="few iterations (CI smoke run)")
    parser.add_argument("--json", action="store_true", help="one JSON document on stdout")
    args = parser.parse_args()
    return args, 20 if args.quick else full
