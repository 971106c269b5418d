"""Argument types of the command line: one parser maker for every numeric option (argparse calls it)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T", int, float)


def number_argument(kind: type[T], expected: str, accept: Callable[[T], bool]) -> Callable[[str], T]:
    """A ``type=`` for argparse: ``kind(text)`` when ``accept`` takes it, else an ``ArgumentTypeError``
    saying ``expected`` (argparse turns it into one ``error:`` line and exit 2)."""
    def parse(text: str) -> T:
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        if not accept(value):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value
    return parse
