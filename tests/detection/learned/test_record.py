"""A run file: events by channel with µs times, 12 significant bits, LZMA members numpy reads back."""
from __future__ import annotations

import numpy as np

from detection.learned.record import RunRecorder, event_times, quantise


def test_a_saved_run_reads_back_within_its_resolution(tmp_path):
    recorder = RunRecorder({})
    rng = np.random.default_rng(0)
    times = 1_795_000_000.0 + np.sort(rng.uniform(-5, 60, 500))
    values = rng.normal(size=(500, 3)) * [1e-3, 1.0, 1e5]
    for t, v in zip(times[::-1], values[::-1]):                   # arrival order does not matter
        recorder.on_event(t, "/faulty/odom", v)
    recorder.ticks = [1_795_000_000.0 + k for k in range(61)]
    recorder.save(tmp_path / "run-000.npz")
    with np.load(tmp_path / "run-000.npz") as data:
        arrays = {k: data[k] for k in data.files}
    np.testing.assert_allclose(event_times(arrays, "/faulty/odom"), times, rtol=0, atol=1e-6)
    np.testing.assert_allclose(arrays["events//faulty/odom/x"], values, rtol=4.9e-4)
    assert event_times(arrays, "/helper/odom") is None


def test_quantise_keeps_twelve_significant_bits_and_exact_small_integers():
    values = np.array([1.0, 4095.0, 921654.0, 3.14159265, -2.5e-7], dtype=np.float32)
    q = quantise(values)
    assert q[0] == 1.0 and q[1] == 4095.0
    np.testing.assert_allclose(q, values, rtol=4.9e-4)
    assert np.all(np.abs(q) <= np.abs(values))


def test_a_process_that_ended_is_lost_not_sampled_as_zeros():
    """An agent that died mid-run stays a zombie until reaped; psutil then reads RSS 0 without an error.
    Those zeros would enter the data as a healthy component's counters: it must be reported lost."""
    import subprocess
    import sys
    import time

    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(1.5)"])   # not reaped until wait()
    recorder = RunRecorder({"short_lived": child.pid}).start()
    try:
        deadline = time.monotonic() + 30
        while not recorder.lost and time.monotonic() < deadline:
            time.sleep(0.2)
    finally:
        recorder.stop()
        child.wait()
    assert recorder.lost == ["short_lived"]
    counters = np.array(recorder.counters["short_lived"])
    assert np.isnan(counters[-1]).all() and not (counters[:, 1] == 0).any()
