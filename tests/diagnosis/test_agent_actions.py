"""The diagnoser called from AgentSpeak: .diagnose / .possibly_faulty (real SAT solver, real interpreter)."""
from __future__ import annotations

from agentspeak.runtime import LocalRuntime


def run(source: str, timeout: float = 30.0) -> list[str]:
    lines: list[str] = []
    rt = LocalRuntime(printer=lambda name, text: lines.append(text))
    rt.add_agent("robot", source)
    rt.run(timeout=timeout)
    return lines


def test_diagnose_returns_every_minimal_diagnosis_and_helper_evidence_narrows_it() -> None:
    lines = run("""
        !go.
        +!go <- .diagnose(turtlebot_hardware, [commanded_forward, ~encoders_report_motion,
                          ~left_over_current, ~right_over_current], D); .print(D);
                .diagnose(turtlebot_hardware, [commanded_forward, ~encoders_report_motion, ~left_over_current,
                          ~right_over_current, helper_found_robot, helper_saw_motion, helper_saw_straight], D2);
                .print(D2).
    """)
    assert lines == [
        "[[left_motor,right_motor],[left_motor,right_encoder],[right_motor,left_encoder],[left_encoder,right_encoder]]",
        "[[left_encoder,right_encoder]]",
    ]


def test_possibly_faulty_and_no_fault_needed() -> None:
    lines = run("""
        !go.
        +!go <- .possibly_faulty(turtlebot_hardware, [commanded_forward, encoders_report_motion,
                                encoders_report_straight], P); .print(P);
                .diagnose(turtlebot_hardware, [commanded_forward, encoders_report_motion,
                          encoders_report_straight], D); .print(D).
    """)
    assert lines == ["[]", "[[]]"]


def test_other_intentions_run_while_the_diagnoser_works() -> None:
    lines = run("""
        !diagnose.
        !count(0).
        +!diagnose <- .diagnose(turtlebot_hardware, [commanded_forward, ~encoders_report_motion,
                                ~left_over_current, ~right_over_current], D);
                      .length(D, N); .print("diagnoses ", N).
        +!count(N) : N < 3 <- .print("count ", N); !count(N + 1).
        +!count(_).
    """)
    assert "diagnoses 4" in lines
    assert lines.index("count 0") < lines.index("diagnoses 4")


def test_unknown_model_and_bad_observations_fail_the_goal_with_a_reason() -> None:
    lines = run("""
        !a. !b.
        +!a <- .diagnose(no_such_model, [x], D).
        -!a[error(E)] <- .print("a ", E).
        +!b <- .diagnose(turtlebot_hardware, [obs(X)], D).
        -!b[error(E)] <- .print("b ", E).
    """)
    assert sorted(lines) == ["a ia_failed", "b wrong_arguments"]
