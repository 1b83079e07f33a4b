"""Locus in Python: a wheeled robot's pose from odometry and range sensors.

The Rust engine of the ``locus`` command line, numpy in and out:

* :func:`replay` -- a recorded log (a file or arrays) through the same
  engine and defaults as ``locus replay``;
* :class:`Filter` -- an EKF over the built-in models, one step at a time
  (``predict``/``update``) or a whole run at once (``run``);
* :func:`simulate` -- the built-in and TOML scenarios of ``locus run``,
  and :func:`monte_carlo` over seeds;
* the models (:class:`DiffDrive`, :class:`Unicycle`, :class:`SkidSteer`;
  :class:`RangeBearing`, :class:`IrPair`, :class:`LaserRange`), each with
  its function and Jacobians (``f``/``jacobians``, ``h``/``jacobian``);
* :mod:`locus.doa` -- paper 002's domain of attraction, one cell or a grid,
  on this machine or a Dask cluster (so do :func:`monte_carlo` and
  :func:`replay_many`: give them a ``dask.distributed.Client``).

Units are SI throughout: metres, radians, seconds. Errors from a log or a
study raise :class:`LocusError` with the message the command line gives
(file, line and field); a bad argument raises ``ValueError`` naming it.
Long calls release the GIL and stop on Ctrl-C.
"""

from ._locus import (
    DiffDrive,
    Filter,
    IrPair,
    LaserRange,
    LocusError,
    RangeBearing,
    SkidSteer,
    Unicycle,
    __version__,
)
from ._replay import Replay, Smoothed, replay, replay_many
from ._simulate import Run, monte_carlo, simulate
from . import doa

__all__ = [
    "DiffDrive",
    "Filter",
    "IrPair",
    "LaserRange",
    "LocusError",
    "RangeBearing",
    "Replay",
    "Run",
    "SkidSteer",
    "Smoothed",
    "Unicycle",
    "doa",
    "monte_carlo",
    "replay",
    "replay_many",
    "simulate",
]
