"""Resuming a study (``regrasp study --resume DIR``): the runs a ``study.json`` holds, checked to be this study's.

A study's run :math:`i` depends only on the study's seed, its perturbation and softness ranges, the scenario, the
plant and the run's length (:mod:`regrasp.study.study`), so the runs an interrupted study finished, or a study of
fewer runs, are runs of the same study asked for again with more: :func:`finished_runs` reads them back (each
checked against its draw, regenerated), and :func:`~regrasp.study.study.run_study` runs only the others. What a
``study.json`` does not record (supervisor settings given from Python) cannot be checked: resume with the same.
"""

from __future__ import annotations

import json
from dataclasses import asdict, fields
from pathlib import Path

from ..core.exceptions import InvalidParameterError
from ..model.perturbation import Perturbation
from ..model.softness import SoftnessRanges
from .draws import draw_runs
from .study import RunOutcome

__all__ = ["finished_runs", "read_study"]


def read_study(path: str | Path, option: str = "resume") -> dict:
    """The ``study.json`` document at ``path`` (a directory: its ``study.json``), or an
    :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``option`` when it is missing or not one."""
    path = Path(path)
    if path.is_dir():
        path = path / "study.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InvalidParameterError(option, str(path), f"a study.json to resume ({exc.strerror or exc})") from None
    except ValueError as exc:
        raise InvalidParameterError(option, str(path), f"a study.json to resume (not JSON: {exc})") from None
    if not isinstance(doc, dict) or not isinstance(doc.get("outcomes"), list):
        raise InvalidParameterError(option, str(path), "a study.json written by regrasp study (no outcomes)")
    return doc


def _plain(value: object) -> object:
    """``value`` as JSON gives it back (tuples as lists, floats exactly)."""
    return json.loads(json.dumps(value))


def finished_runs(doc: dict, *, scenario: str, contacts: int, plant: str, duration: float, seed: int, runs: int,
                  perturbation: Perturbation, softness: SoftnessRanges | None,
                  option: str = "resume") -> tuple[RunOutcome, ...]:
    """The outcomes ``doc`` (a ``study.json``, :func:`read_study`) holds, as this study's (``scenario``: its file or
    name, ``contacts`` its fingers; the rest :func:`~regrasp.study.study.run_study`'s arguments, ``duration`` each
    run's resolved length [s]): an :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``option`` and the
    first thing that differs when it is another study's, or holds more runs than ``runs``."""
    expected = {"scenario": Path(str(scenario)).name, "plant": plant, "seed": seed, "duration": duration,
                "perturbation": _plain(asdict(perturbation)),
                "softness": None if softness is None else _plain(asdict(softness))}
    found = {**{k: doc.get(k) for k in expected}, "scenario": Path(str(doc.get("scenario"))).name}
    for key, value in expected.items():
        if found[key] != value:
            raise InvalidParameterError(option, doc.get("scenario"), f"a study.json of this study ({key}: it has "
                                        f"{found[key]!r}, this study {value!r})")
    outcomes = doc["outcomes"]
    indices = [o.get("draw", {}).get("index") if isinstance(o, dict) else None for o in outcomes]
    if any(not isinstance(i, int) or not 0 <= i < runs for i in indices) or len(set(indices)) != len(indices):
        raise InvalidParameterError(option, doc.get("scenario"), f"at most {runs} runs, once each (it holds runs "
                                    f"{sorted(i for i in indices if isinstance(i, int))[-3:]}...; ask for more runs)")
    draws = draw_runs(runs, seed, perturbation, contacts, softness)
    names = [f.name for f in fields(RunOutcome) if f.name != "draw"]
    out = []
    for o, i in zip(outcomes, indices):
        if o["draw"] != _plain(draws[i].to_json_dict()):
            raise InvalidParameterError(option, doc.get("scenario"), f"a study.json of this study (run {i} drew "
                                        "other model errors: another perturbation, softness or number of fingers)")
        try:
            out.append(RunOutcome(draws[i], **{n: o[n] for n in names}))
        except KeyError as exc:
            raise InvalidParameterError(option, doc.get("scenario"), f"complete outcomes (run {i} has no "
                                        f"{exc.args[0]})") from None
    return tuple(out)
