"""DiagnosisService: futures solved on worker threads, the model cache, AgentSpeak observation literals."""
from __future__ import annotations

import os
import threading

import pytest

from diagnosis.service import DiagnosisService, observation_of, observations_of

LAMP = """\
system: lamp
components: [bulb, switch]
observations: [on, lit]
variables: [current]
behaviour:
  - "!AB(switch) -> (current <-> on)"
  - "!AB(bulb) -> (lit <-> current)"
"""


def test_agentspeak_literals_map_to_named_observations():
    assert observation_of("moved") == ("moved", True)
    assert observation_of("~moved") == ("moved", False)
    assert observation_of("hz(scan)") == ("hz(scan)", True)
    assert observation_of("~timing(scan, pose)") == ("timing(scan,pose)", False)
    assert observations_of(["on", "~lit"]) == {"on": True, "lit": False}
    with pytest.raises(ValueError, match="both as true and as false"):
        observations_of(["on", "~on"])


def test_queries_run_on_worker_threads_and_return_futures(write):
    path = write("lamp.yaml", LAMP)
    with DiagnosisService() as service:
        future = service.submit(path, observations_of(["on", "~lit"]))
        result = future.result(timeout=30)
        assert result.diagnoses == [["bulb"], ["switch"]] and result.complete
        assert service.submit_possibly_faulty(path, {"on": True, "lit": False}).result(30) == ["bulb", "switch"]
        worker = service._pool.submit(threading.current_thread).result(30)
        assert worker is not threading.main_thread()


def test_bad_observations_fail_the_future_not_the_caller(write):
    path = write("lamp.yaml", LAMP)
    with DiagnosisService() as service:
        future = service.submit(path, {"dark": True})
        with pytest.raises(KeyError, match="unknown observation 'dark'"):
            future.result(timeout=30)


def test_models_are_cached_and_reloaded_when_the_file_changes(write):
    path = write("lamp.yaml", LAMP)
    with DiagnosisService() as service:
        first = service.diagnoser(path)
        assert service.diagnoser(path) is first
        path.write_text(LAMP.replace("components: [bulb, switch]", "components: [bulb, switch, plug]"))
        st = os.stat(path)
        os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
        second = service.diagnoser(path)
        assert second is not first and second.model.components == ("bulb", "switch", "plug")


def test_concurrent_queries_on_one_and_on_several_models(write):
    lamp = write("lamp.yaml", LAMP)
    other = write("other.yaml", LAMP.replace("system: lamp", "system: other"))
    with DiagnosisService(workers=4) as service:
        futures = [service.submit(path, {"on": True, "lit": bool(i % 2)})
                   for i in range(20) for path in (lamp, other)]
        answers = [f.result(timeout=60).diagnoses for f in futures]
    assert answers == [[["bulb"], ["switch"]] if i % 2 == 0 else [[]] for i in range(20) for _ in range(2)]
