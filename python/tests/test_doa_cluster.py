"""locus.doa over Dask: the grid's CSV is exactly `locus doa`'s, on a
LocalCluster and on a scheduler with worker processes started on loopback."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest

import locus
import locus.doa

SMALL = "[grid]\nv_g_count = 3\nalpha_count = 4\n"


@pytest.fixture(scope="module")
def study(tmp_path_factory, locus_bin):
    """A 3 x 4 grid, and the CSV the command line writes for it."""
    d = tmp_path_factory.mktemp("doa")
    config = d / "small.toml"
    config.write_text(SMALL)
    subprocess.run([locus_bin, "doa", config, "--out", d / "cli", "--no-plots"], check=True,
                   capture_output=True)
    return config, (d / "cli" / "doa.csv").read_text()


def test_here_equals_the_command_line(study):
    config, cli = study
    grid = locus.doa.grid(config)
    assert grid.csv == cli
    assert grid.m_zeta.shape == (3, 4)
    cell = locus.doa.cell(1, 2, config)
    assert cell["m_zeta"] == grid.m_zeta[1, 2]


def test_a_local_cluster_of_two_workers_equals_the_command_line(study):
    from dask.distributed import Client, LocalCluster

    config, cli = study
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address=None) as cluster, Client(cluster) as client:
        grid = locus.doa.grid(config, client=client)
        # Shards of other sizes merge back to the same bytes.
        odd = locus.doa.grid(config, client=client, shards=5)
    assert grid.csv == cli
    assert odd.csv == cli


def test_a_scheduler_and_two_worker_processes_on_loopback_equal_the_command_line(study, tmp_path):
    from dask.distributed import Client

    config, cli = study
    file = tmp_path / "scheduler.json"
    env = dict(os.environ)
    scheduler = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_scheduler",
                                  "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", file], env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    worker = None
    try:
        for _ in range(300):
            if file.exists() and file.stat().st_size > 0:
                break
            time.sleep(0.1)
        worker = subprocess.Popen([sys.executable, "-m", "distributed.cli.dask_worker",
                                   "--scheduler-file", file, "--nworkers", "2", "--nthreads", "1",
                                   "--host", "127.0.0.1", "--no-dashboard"], env=env,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with Client(scheduler_file=str(file), timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
            assert str(client.scheduler.address).startswith("tcp://127.0.0.1:")
            grid = locus.doa.grid(config, client=client)
            runs = locus.monte_carlo("wall45", seeds=[1, 2, 3], client=client)
    finally:
        for p in (worker, scheduler):
            if p is not None:
                p.terminate()
                p.wait(timeout=30)
    assert grid.csv == cli
    here = [locus.simulate("wall45", seed=s) for s in (1, 2, 3)]
    for a, b in zip(runs, here):
        assert a.results == {**b.results, "timing": a.results["timing"]}
        assert a.columns.keys() == b.columns.keys()
        for name in b.columns:
            np.testing.assert_array_equal(a.columns[name], b.columns[name])
