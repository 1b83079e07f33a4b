"""Paper 002's domain of attraction (``locus doa``): one cell, or the
``(v_g, alpha)`` grid on this machine or over a Dask cluster.

The grid's CSV is byte for byte what ``locus doa`` writes (``doa.csv``):
on a cluster each task computes one deterministic shard
(``locus doa --shard I/N``), and the shards merge back exactly
(``locus doa merge``).

>>> import locus.doa
>>> grid = locus.doa.grid("study.toml")                 # all cores here
>>> from dask.distributed import Client
>>> grid = locus.doa.grid("study.toml", client=Client("tcp://scheduler:8786"))
>>> grid.m_zeta.shape                                   # (v_g count, alpha count)
"""

from __future__ import annotations

import io
import os
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from . import _locus

PathLike = Union[str, os.PathLike]


def _config(config: Optional[PathLike]):
    """The configuration's TOML text and name (None: the spec's defaults)."""
    if config is None:
        return None, "defaults"
    with open(config, encoding="utf-8") as f:
        return f.read(), os.fspath(config)


@dataclass(frozen=True)
class Grid:
    """A domain-of-attraction grid: rows are ``v_g`` values, columns
    ``alpha`` values."""

    csv: str
    """The CSV, as ``locus doa`` writes ``doa.csv``."""
    v_g: np.ndarray
    """(R,): the rows' observer gain ``v_g`` [1/s]."""
    alpha: np.ndarray
    """(C,): the columns' ``alpha`` [-]."""
    m_zeta: np.ndarray
    """(R, C): the largest initial error ``M_zeta`` from which every vertex converges."""
    settle_time_s: np.ndarray
    """(R, C): the worst settling time [s]; NaN where some vertex did not converge."""
    evaluations: np.ndarray
    """(R, C): simulations the search ran per cell."""

    def to_csv(self, path: PathLike) -> None:
        """Writes the CSV to ``path``."""
        with open(path, "w", encoding="utf-8", newline="") as f:
            f.write(self.csv)

    @classmethod
    def from_csv(cls, text: str) -> "Grid":
        lines = [l for l in text.splitlines() if not l.startswith("#")]
        data = np.genfromtxt(io.StringIO("\n".join(lines[1:])), delimiter=",", dtype=np.float64,
                             ndmin=2)
        i, j = data[:, 1].astype(int), data[:, 2].astype(int)
        shape = (i.max() + 1, j.max() + 1)
        def table(col):
            out = np.full(shape, np.nan)
            out[i, j] = data[:, col]
            return out
        return cls(csv=text, v_g=table(3)[:, 0], alpha=table(4)[0, :], m_zeta=table(5),
                   settle_time_s=table(7), evaluations=table(6).astype(np.int64))


def _shard(index: int, count: int, config: Optional[str], name: str, threads: Optional[int]) -> str:
    return _locus.doa_shard(config, name=name, index=index, count=count, threads=threads)


def grid(config: Optional[PathLike] = None, client: Optional[Any] = None,
         shards: Optional[int] = None, threads: Optional[int] = None) -> Grid:
    """The whole grid of the study configured by the TOML file ``config``
    (None: the spec's 12 x 25 grid).

    Without ``client`` it runs here on ``threads`` threads (default: all
    cores). With a ``dask.distributed.Client`` the grid is cut into
    ``shards`` shards (default: 4 per worker thread of the cluster), one
    task each, each on ``threads`` threads of its worker (default 1), and
    merged back: the same CSV as ``locus doa``.
    """
    text, name = _config(config)
    if client is None:
        return Grid.from_csv(_locus.doa_shard(text, name=name, index=0, count=1, threads=threads))
    if shards is None:
        shards = 4 * max(1, sum(client.nthreads().values()))
    futures = client.map(_shard, range(shards), count=shards, config=text, name=name,
                         threads=threads or 1, pure=False)
    parts = client.gather(futures)
    return Grid.from_csv(_locus.doa_merge(parts, config=text, name=name))


def cell(i_vg: int, i_alpha: int, config: Optional[PathLike] = None) -> dict:
    """One cell of the grid, row ``i_vg`` and column ``i_alpha``: its
    ``v_g`` [1/s], ``alpha``, ``m_zeta``, the search's ``evaluations`` and
    the worst ``settle_time_s`` (None if some vertex did not converge)."""
    text, name = _config(config)
    v_g, alpha, m_zeta, evaluations, settle = _locus.doa_cell(i_vg, i_alpha, text, name)
    return {"v_g": v_g, "alpha": alpha, "m_zeta": m_zeta, "evaluations": evaluations,
            "settle_time_s": settle}
