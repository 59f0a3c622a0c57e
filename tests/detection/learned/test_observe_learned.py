"""``faultmas observe --learned MODELS_DIR``: the learned ``resource`` observer in the same pipeline as the
other observers. On bad input one clear line and exit 2; on the live team (real node processes, a
memory leak injected through the perf-bug hook) ``~resource(C)`` reaches the diagnoser, which names C;
the run recorded with ``--record`` and replayed with ``--bag`` gives the same verdicts."""
from __future__ import annotations

import json
import subprocess
import sys
import threading
import time

import pytest

from agents.cli import main

from ..conftest import interrupt
from tests.ros_domain import ros_domain  # noqa: E402

LEAKING = "helper_motion_decomposer"


def test_bad_learned_input_gives_one_clear_line(tmp_path, capsys):
    assert main(["observe"]) == 2
    assert "nothing to observe: give CONFIG.yaml, --learned MODELS_DIR, or both" in capsys.readouterr().err
    assert main(["observe", "--learned", str(tmp_path)]) == 2
    assert f"{tmp_path}: no model files (*.npz)" in capsys.readouterr().err
    (tmp_path / "faulty_kobuki_sim.npz").write_bytes(b"not a model")
    assert main(["observe", "--learned", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "faulty_kobuki_sim.npz" in err and "Traceback" not in err
    assert main(["observe", "--learned", str(tmp_path), "--bag", "x.mcap", "--zenoh"]) == 2
    assert "--bag replays a recording; it cannot be used with --zenoh" in capsys.readouterr().err


def test_a_bag_without_the_learned_recording_is_refused_clearly(smoke, smoke_evaluation, tmp_path, capsys):
    """``--bag --learned`` needs what ``--learned --record`` writes: the models' topics and the ticks."""
    pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")
    from rclpy.serialization import serialize_message

    from detection.learned.encoding import RosEncoder
    from detection.message import Message
    from detection.taps.bag import BagRecorder

    models = tmp_path / "models"
    models.mkdir()
    for name, model in smoke_evaluation.models.items():
        model.save(models / f"{name}.npz")
    channels = json.loads((smoke.path / "manifest.json").read_text())["runs"][0]["channels"]

    def bag(name: str, topics: dict[str, str]):
        recorder = BagRecorder(tmp_path / name)
        recorder.start(10**9)
        for k, (topic, msgtype) in enumerate(topics.items()):
            raw = serialize_message(RosEncoder.for_type(msgtype).msg_class())
            recorder.write(Message(topic, 10**9 + k, raw=raw), msgtype)
        recorder.close()
        return str(tmp_path / name)

    for name, topics in (("unrelated", {"/elsewhere": "std_msgs/msg/String"}),
                         ("untimed", {topic: c["type"] for topic, c in channels.items()})):
        assert main(["observe", "--bag", bag(name, topics), "--learned", str(models)]) == 2
        err = capsys.readouterr().err
        assert "no learned ticks in this bag: record it with 'faultmas observe --learned MODELS_DIR --record PATH'" \
            in err and "Traceback" not in err
    assert main(["observe", "--bag", str(tmp_path / "absent"), "--learned", str(models)]) == 2
    assert "no such bag" in capsys.readouterr().err


@pytest.mark.timeout(360)
def test_observe_learned_names_the_leaking_node_live(smoke_evaluation, tmp_path):
    pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")
    import rclpy

    from detection.learned.scenario import ROBOTS, Workload
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.perfbugs import ENV_VAR, PerfBug, write_schedule
    from robot_bridge.ros2.runtime import RosContext, loopback_env

    domain = ros_domain(53)
    models = tmp_path / "models"
    models.mkdir()
    for name, model in smoke_evaluation.models.items():
        model.save(models / f"{name}.npz")
    schedule = tmp_path / "schedule.json"
    write_schedule(schedule, [])
    supervisor = Supervisor(plan(list(ROBOTS), camera=False, seed=12), domain, extra_env={ENV_VAR: str(schedule)})
    supervisor.start()
    observe = None
    lines: list[str] = []
    try:
        assert supervisor.wait_ready(90) == set()
        with RosContext(domain_id=domain) as work:
            Workload(work.add(rclpy.create_node("perfbugs_workload", context=work.context)), ROBOTS, seed=12)
            observe = subprocess.Popen([sys.executable, "-m", "agents", "observe", "--learned", str(models), "--json",
                                        "--domain-id", str(domain), "--duration", "150", "--record", "run"],
                                       cwd=tmp_path, text=True,
                                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=loopback_env())
            reader = threading.Thread(target=lambda: lines.extend(observe.stdout), daemon=True)
            reader.start()
            first = time.monotonic()
            while not lines and time.monotonic() < first + 60 and observe.poll() is None:
                time.sleep(0.2)                          # the first verdicts: the observer is watching
            assert lines, (observe.poll(), observe.stderr.read() if observe.poll() is not None else "")
            time.sleep(5.0)
            start = time.time()
            write_schedule(schedule, [PerfBug(LEAKING, "memory_leak", start, start + 120.0)])
            named = None
            while named is None and time.time() < start + 80.0 and observe.poll() is None:
                for line in list(lines):
                    update = json.loads(line)
                    if f"~resource({LEAKING})" in update["obs"] and update["diagnoses"] \
                            and all(LEAKING in d for d in update["diagnoses"]):
                        named = update
                time.sleep(0.5)
    finally:
        try:
            if observe is not None:
                interrupt(observe)                       # Ctrl-C ends it cleanly
        finally:
            supervisor.stop()
    err = observe.stderr.read()
    assert named is not None, (lines[-3:], err[-2000:])
    assert observe.returncode == 0, err[-2000:]
    assert "learned resource observer watching" in err and LEAKING in err
    leak = next(c for line in lines for c in json.loads(line)["changed"] if c["literal"] == f"~resource({LEAKING})")
    assert leak["source"] == "learned" and leak["measured"] > smoke_evaluation.models[LEAKING].threshold

    # the recording (the models' topics and each tick's counters) replayed: the same verdicts, offline
    replayed = subprocess.run([sys.executable, "-m", "agents", "observe", "--bag", "run", "--learned", str(models),
                               "--json"], cwd=tmp_path, text=True, capture_output=True, timeout=120)
    assert replayed.returncode == 0, replayed.stderr[-2000:]
    live_changes = [(c["literal"], c["time"]) for line in lines for c in json.loads(line)["changed"]]
    replay_changes = [(c["literal"], c["time"]) for line in replayed.stdout.splitlines()
                      for c in json.loads(line)["changed"]]
    assert (f"~resource({LEAKING})", leak["time"]) in replay_changes
    assert replay_changes[:len(live_changes)] == live_changes, (live_changes, replay_changes)


def test_the_status_table_shows_the_learned_verdicts_beside_the_observers():
    import io

    from detection.observation import Observation
    from detection.session import open_session
    from detection.status import StatusTable

    session = open_session(None)                               # --learned alone: no configured observer
    table = StatusTable(session.observers, io.StringIO())
    session.pipeline.add_listener(table.record)
    session.pipeline.observe([Observation(f"resource({LEAKING})", False, 1.0, measured=812.5, source="learned")])
    row = table.render().splitlines()[1].split()
    assert row == [f"resource({LEAKING})", "learned", "812.5", "FAULT"]
    session.close()

