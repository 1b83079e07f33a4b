"""Ctrl-C stops a long call at once: the call raises KeyboardInterrupt
rather than running to its end."""

import os
import signal
import subprocess
import sys


def test_ctrl_c_stops_a_long_call(tmp_path):
    config = tmp_path / "big.toml"
    # Four times the default grid: minutes of work on two cores.
    config.write_text("[grid]\nv_g_count = 24\nalpha_count = 50\n")
    # Ctrl-C as an interactive session sees it: Python's handler installed
    # even when this test runs in the background, whose SIGINT a shell
    # sets to ignored (and a child inherits).
    code = ("import signal\n"
            "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
            "import locus.doa, sys\n"
            "print('started', flush=True)\n"
            f"locus.doa.grid({str(config)!r})\n"
            "print('finished', flush=True)\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, env=os.environ)
    try:
        assert p.stdout.readline().strip() == "started"
        # Into the sweep (the import is done; the call has begun).
        import time
        time.sleep(1.0)
        p.send_signal(signal.SIGINT)
        out, err = p.communicate(timeout=30)
    finally:
        if p.poll() is None:
            p.kill()
    assert "KeyboardInterrupt" in err, err
    assert "finished" not in out
    assert p.returncode != 0
