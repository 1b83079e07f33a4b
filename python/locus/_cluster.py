"""Spreading independent calls over a Dask cluster, or over threads here.

Dask is the engine: with a ``dask.distributed.Client`` each item becomes a
task on the cluster's workers (which must have ``locus`` installed, the
same version); without one the items run on a thread pool of this process
(Locus releases the GIL, so the threads run in parallel).
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from typing import Any, Callable, Iterable, List, Optional


def spread(fn: Callable[..., Any], items: Iterable[Any], client: Optional[Any] = None,
           threads: Optional[int] = None, **kwargs: Any) -> List[Any]:
    """``[fn(item, **kwargs) for item in items]``, in order, over ``client``'s
    workers or over ``threads`` threads here (default: the cores)."""
    items = list(items)
    if client is not None:
        futures = client.map(fn, items, pure=False, **kwargs)
        return client.gather(futures)
    with ThreadPoolExecutor(max_workers=threads or os.cpu_count() or 1) as pool:
        return list(pool.map(lambda item: fn(item, **kwargs), items))
