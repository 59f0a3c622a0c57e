"""The runner of Jason's unit suite (``make jason-tests``) fails, naming what is missing, when tests go
uncounted: a tester killed mid-test, or a manager that ends "PASSED" with half the count (one loaded run
reported "228 executed / 228 passed" and exit 0 where Java Jason executes 468)."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.jason_suite.__main__ import DEFAULT_DIR, SuiteRun, judge, run_suite

JASON_INC = DEFAULT_DIR / "src/test/jason/inc"
pytestmark = pytest.mark.skipif(not JASON_INC.is_dir(), reason=f"Jason's unit suite is not at {DEFAULT_DIR}")

MAS = """MAS mini {{
    agents:
        test_manager [ goals="create_tester_agents(\\"./src/test/jason\\",\\".*.asl\\",\\"/inc\\")",
                       beliefs="shutdown_delay(4)" ];
    aslSourcePath: "{inc}"; "src/test/jason/asl";
}}
"""
ALPHA = """{ include("tester_agent.asl") }
@[test]
+!test_alpha <- !assert_true(true).
"""
VICTIM = """{ include("tester_agent.asl") }
@[test]
+!test_victim <- .wait(1500); !assert_true(true).
"""
KILLER = """{ include("tester_agent.asl") }
@[test]
+!test_killer <- .kill_agent(victim); !assert_true(true).
"""


def mini_suite(root: Path) -> Path:
    """A suite laid out as Jason's, run by Jason's own test manager (read in place): ``alpha`` passes its
    one test, ``victim`` is killed by ``zz_killer`` (created after it) while its test waits."""
    jason = root / "src/test/jason"
    (jason / "inc").mkdir(parents=True)     # the manager leaves this folder out; ours is empty
    (jason / "asl").mkdir()
    (jason / "unit_tests.mas2j").write_text(MAS.format(inc=JASON_INC))
    (jason / "asl/alpha.asl").write_text(ALPHA)
    (jason / "asl/victim.asl").write_text(VICTIM)
    (jason / "asl/zz_killer.asl").write_text(KILLER)
    return root


def test_a_tester_killed_mid_test_fails_the_run_and_is_named(tmp_path):
    suite = mini_suite(tmp_path)
    run = run_suite(suite, timeout=60, expect=3)
    assert run.summary_found and (run.executed, run.passed) == (2, 2)      # the count alone looks clean
    assert not run.ok
    problems = "\n".join(run.problems)
    assert "exited with code 1" in problems            # the manager's .stopMAS(0,1), passed on as Jason does
    assert "did not say 'End of Jason unit tests: PASSED'" in problems
    assert "only 2 tests executed, 3 expected" in problems
    assert "1 of 3 tester agents printed nothing (never ran?): victim" in problems
    runner = subprocess.run([sys.executable, "-m", "tests.jason_suite", str(suite), "--expect", "3",
                             "--timeout", "60"], capture_output=True, text=True, cwd=Path(__file__).parents[2])
    assert runner.returncode == 1, runner.stdout + runner.stderr


def test_a_passed_summary_with_half_the_tests_fails():
    output = ("[test_manager] #228 tests executed, #228 PASSED and #0 failed.\n"
              "[test_manager] End of Jason unit tests: PASSED\n[alpha] assert_true on event 'test_a' PASSED\n")
    run = judge(SuiteRun(0, output), testers=["alpha", "beta"], expect=468)
    assert run.problems == ["only 228 tests executed, 468 expected",
                            "1 of 2 tester agents printed nothing (never ran?): beta"]
    complete = judge(SuiteRun(0, output.replace("228", "468") + "[beta] x\n"), ["alpha", "beta"], 468)
    assert complete.ok
