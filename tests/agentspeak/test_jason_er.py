"""Jason(ER) sub-plans and goal conditions, written from Jason 3.3.2's sources (jason-lang/jason:
``TransitionSystem.applySelEv``/``applyRelApplPlRule1``/``applyClrInt``, ``stdlib/done.java``) and its
``examples/contract-net-protocol-er`` (which these small programs imitate, without its files)."""
from __future__ import annotations

import textwrap

import pytest

from agentspeak.errors import AslSyntaxError
from agentspeak.parser import parse_program
from tests.agentspeak.harness import run_asl, run_mas


def asl(text: str) -> str:
    return textwrap.dedent(text).strip() + "\n"


def test_sub_plans_parse_after_a_plan_and_a_directive_may_still_follow():
    program = parse_program(asl("""
        +!g(X) <- !s. {
            +!s <- .print(X).
            +!t <- true. { +!u <- true. }
        }
        { register_function("my.f", 1, "f") }
        f(X, X).
    """))
    (plan,) = program.plans
    assert [str(p.trigger) for p in plan.sub_plans] == ["+!s", "+!t"]
    assert [str(p.trigger) for p in plan.sub_plans[1].sub_plans] == ["+!u"]


def test_a_block_of_sub_plans_without_a_plan_before_it_is_a_located_error():
    with pytest.raises(AslSyntaxError) as exc:
        parse_program("b(1).\n{ +!s <- true. }\n", "x.asl")
    assert exc.value.line == 2 and "must follow a plan" in str(exc.value)


def test_sub_plans_see_the_variables_of_their_plan_and_are_relevant_only_while_it_runs():
    out = run_asl(asl("""
        !cnp(1, fix).
        !later.
        +!cnp(Id, Task) <- !call(LP); .print(LP). {
            +!call([Id, Task | X]) <- !inner(X).
            +!inner(Y) : Id > 0 <- Y = []; !deep. {
                +!deep <- .print(deep, Id, Task).
            }
        }
        +!later <- .wait(100); !call(Z).
        -!later[error(E)] <- .print(E).
    """), timeout=5)
    assert out == ["deep1fix", "[1,fix]", "no_relevant"]


def test_a_sub_plan_shadows_an_outer_plan_and_the_outer_one_is_found_when_it_does_not_apply():
    out = run_asl(asl("""
        !a.
        +!a <- !s(1); !s(2). {
            +!s(1) <- .print(inner).
        }
        +!s(N) <- .print(outer, N).
    """))
    assert out == ["inner", "outer2"]


def test_a_goal_condition_makes_a_finished_body_wait_until_done():
    # applyClrInt: an intended means with a goal condition whose body is over moves to the pending
    # intentions (wait_goal_condition); only the condition, .done or .succeed_goal finish it
    out = run_asl(asl("""
        !g.
        !h.
        +!g <: false <- .print(body_over).
        +!h <- .wait(100); !show; .succeed_goal(g); !show.
        +!show : .intend(g) <- .print(yes).
        +!show <- .print(no).
    """))
    assert out == ["body_over", "yes", "no"]


def test_done_without_argument_achieves_the_running_plans_goal():
    out = run_asl(asl("""
        !top.
        +!top <- !w; .print(after_w).
        +!w <: false <- .print(in_w); .done; .print(never).
    """))
    assert out == ["in_w", "after_w"]


def test_a_belief_update_runs_a_sub_plan_on_a_branch_and_done_finishes_the_goal():
    # applySelEv: an external +b with an applicable sub-plan of an intended means runs that sub-plan
    # with the intended means' bindings; .done there finishes the goal whose sub-plan it is
    out = run_asl(asl("""
        !bids(2).
        !offers.
        +!bids(N) <: false <- .print(waiting, N); .wait(3000); .print(timed_out). {
            +offer(V) : .count(offer(_), C) & C >= N <- .print(all, C); .done.
            +offer(V) <- .print(got, V).
        }
        +!offers <- .wait(100); ++offer(10); .wait(50); ++offer(20); .wait(100); .print(end).
        +offer(V) <- .print(root, V).
    """), timeout=5)
    # ++b: the event of a new intention, external as a percept or a message is (a branch needs one)
    assert "waiting2" == out[0]
    assert set(out[1:5]) == {"got10", "root10", "all2", "root20"}
    assert out[5:] == ["end"]


def test_without_the_intention_the_sub_plan_is_not_relevant():
    out = run_asl(asl("""
        !go.
        +!go <- ++offer(1); .wait(50); .print(done).
        +!bids <: false <- .wait(10). { +offer(V) <- .print(sub, V). }
    """))
    assert out == ["done"]


def test_contract_net_with_sub_plans_between_agents():
    # the shape of examples/contract-net-protocol-er (c_alt and p): a participant's +cfp plan waits
    # (goal condition false) until a sub-plan for accept/reject says .done
    initiator = asl("""
        !cnp(1, fix).
        +!cnp(Id, Task) <- .send([p1, p2], tell, cfp(Id, Task)); !bids; !winner(W); .print(winner, W). {
            +!bids <: false <- .wait(3000); .done. {
                +propose(Id, _) : .count(propose(Id, _)[source(_)], 2) <- .done.
            }
            +!winner(A) : .findall(offer(O, Ag), propose(Id, O)[source(Ag)], L) & .min(L, offer(_, A))
               <- for (.member(offer(_, Ag), L)) {
                      if (Ag == A) { .send(Ag, tell, accept(Id)) } else { .send(Ag, tell, reject(Id)) }
                  }.
        }
    """)
    participant = asl("""
        price(p1, 10).
        price(p2, 5).
        +cfp(Id, Task)[source(A)] : .my_name(Me) & price(Me, P) <: false <- .send(A, tell, propose(Id, P)). {
            +accept(Id) <- .print(won, Task); .done.
            +reject(Id) <- .print(lost, Task); .done.
        }
    """)
    out = run_mas({"c": initiator, "p1": participant, "p2": participant}, timeout=8)
    assert "[c] winnerp2" in out
    assert "[p2] wonfix" in out and "[p1] lostfix" in out
    assert out.index("[c] winnerp2") < out.index("[p2] wonfix")


def test_a_failure_plan_among_the_sub_plans_handles_a_failed_sub_goal():
    out = run_asl(asl("""
        !cnp(7).
        +!cnp(Id) <- !bids; .print(after, Id). {
            +!bids <- .fail.
            -!bids <- .print(no_bids, Id).
        }
    """))
    assert out == ["no_bids7", "after7"]
