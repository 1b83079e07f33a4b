"""``locus.simulate``: the scenarios of ``locus run``, numpy out."""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Optional, Union

import numpy as np

from . import _locus
from ._cluster import spread


@dataclass(frozen=True)
class Run:
    """One simulated run: its log's columns (``locus run``'s ``log.csv``,
    the names with their units) and its results (the results schema's
    figures: accuracy against the truth, 3-sigma shares, NEES)."""

    scenario: str
    seed: int
    columns: Dict[str, np.ndarray]
    results: dict

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    def to_pandas(self):
        """The log as a pandas DataFrame (pandas must be installed)."""
        import pandas as pd

        return pd.DataFrame(self.columns)


def simulate(scenario: Union[str, os.PathLike] = "square", seed: int = 1,
             guide_step: Optional[str] = None) -> Run:
    """Runs a built-in scenario (``square``, ``square-ideal``, ``wall45``,
    ``tricycle-slip``, ``hover``) or a TOML scenario file, as ``locus run``
    does, from ``seed``. ``guide_step`` ("a" to "f") configures the square
    as that step of paper 001's guided experiment."""
    name = os.fspath(scenario)
    raw = _locus.simulate(name, seed, guide_step)
    return Run(scenario=name, seed=seed, columns=raw["columns"], results=json.loads(raw["results"]))


def _one(seed: int, scenario: str, guide_step: Optional[str]) -> Run:
    return simulate(scenario, seed, guide_step)


def monte_carlo(scenario: Union[str, os.PathLike] = "square", seeds: Iterable[int] = range(1, 11),
                guide_step: Optional[str] = None, client: Optional[Any] = None) -> List[Run]:
    """One run per seed, over a Dask ``client``'s workers or this machine's
    cores (see :func:`locus.simulate`)."""
    return spread(_one, seeds, client, scenario=os.fspath(scenario), guide_step=guide_step)
