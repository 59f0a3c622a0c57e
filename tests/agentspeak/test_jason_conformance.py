"""Jason 3.3 behaviours that Jason's own unit tests and demos rely on (issue 21), one test each, written
from Jason's documentation and sources (``jason-lang/jason``, cited per test)."""
from __future__ import annotations

import os
import textwrap

import pytest

from agentspeak.mas2j import parse_mas2j
from agentspeak.parser import parse_program
from tests.agentspeak.harness import run_asl, run_asl_logged, run_mas


def asl(text: str) -> str:
    return textwrap.dedent(text)


# -- belief updates in a plan body ------------------------------------------------------------------
@pytest.mark.parametrize("op", ["+b", "-b", "-+b"])
def test_formula_after_a_belief_update_with_a_reacting_plan_runs(op):
    # TransitionSystem: +b/-b with a relevant plan is an internal event of the same intention; the plan
    # that posted it goes on once the reacting plan is done
    out = run_asl(asl(f"""
        b.
        !g.
        +!g <- {op}; .print(after).
        +b <- .print(added).
        -b <- .print(removed).
    """))
    assert out[-1] == "after"
    assert len(out) >= 2


# -- goal-state meta events (GoalListenerForMetaEvents) ---------------------------------------------
def test_goal_state_meta_events_follow_a_goal_through_its_life():
    out = run_asl(asl("""
        !start.
        +!start <- !t1; !t2.
        +!t1 <- X = 1; X = 2.
        -!t1[error(E)] <- .print(handled(E)).
        +!t2 <- .print(t2).
        ^!t1[state(S)] <- .print(t1(S)).
        ^!t2[state(S)] <- .print(t2(S)).
    """))
    for state in ("pending", "executing", "failed", "achieved", "finished"):
        assert f"t1({state})" in out
    assert "handled(constraint_failed)" in out
    assert out.index("t2(executing)") < out.index("t2(achieved)")


def test_meta_event_state_has_a_reason_annotation():
    out = run_asl(asl("""
        !g.
        +!g <- true.
        ^!g[state(achieved)[reason(R)]] <- .print(reason(R)).
    """))
    assert out == ['reason("")']


# -- hard_deadline ------------------------------------------------------------------------------------
def test_hard_deadline_fails_the_goal_with_deadline_reached():
    # TransitionSystem.checkHardDeadline: !g[hard_deadline(MS)] fails g when it is still pursued MS ms later
    out = run_asl(asl("""
        !start.
        +!start <- !g[hard_deadline(100)]; .print(after).
        +!g <- .wait(2000); .print(too_late).
        -!g[error(E)] <- .print(failed(E)).
    """), timeout=10)
    assert out == ["failed(deadline_reached)", "after"]


def test_hard_deadline_does_not_fire_after_the_goal_is_achieved():
    out = run_asl(asl("""
        !start.
        +!start <- !g[hard_deadline(100)]; .wait(300); .print(after).
        +!g <- .print(done).
        -!g[error(E)] <- .print(failed(E)).
    """), timeout=3)
    assert out == ["done", "after"]


# -- goal conditions (Jason 3.2, TransitionSystem.applyClrSatInt) ------------------------------------
def test_goal_condition_parses_and_achieves_the_goal_when_it_holds():
    program = parse_program("+!g <: done <- .wait(5000).")
    assert program.plans[0].goal_condition is not None
    out = run_asl(asl("""
        !g.
        !set.
        +!g <: done <- .wait(3000); .print(timed_out).
        +!set <- .wait(50); +done.
        ^!g[state(achieved)] <- .print(achieved).
    """), timeout=10)
    assert out == ["achieved"]


# -- annotations ---------------------------------------------------------------------------------------
def test_annotation_list_with_only_a_tail():
    out = run_asl(asl("""
        p(1)[a,b].
        !g.
        +!g <- ?p(1)[|As]; .print(As).
    """))
    assert out == ["[a,b,source(self)]"]


@pytest.mark.parametrize("pattern, term, expected", [
    ("L[test]", "l1[atomic,test]", "l1"),
    ("_[test]", "l1[test]", "ok"),
    ("N[H|T]", "b[atomic,test]", "b atomic [test]"),
])
def test_variable_with_annotations_unifies_as_jason(pattern, term, expected):
    # Unifier.unifiesNoUndo: the variable's annotations are a subset of the literal's, and the variable
    # is bound to the literal without annotations
    out = run_asl(asl(f"""
        !g.
        +!g <- {pattern} = {term}; .print({'"ok"' if pattern.startswith('_') else ', " ", '.join(
            v for v in ("L", "N", "H", "T") if v in pattern)}).
    """))
    assert out == [expected]


def test_failure_plan_with_an_annotated_variable_trigger_handles_any_goal():
    out = run_asl(asl("""
        !g.
        +!g <- .fail.
        -!F[error(E)] <- .print(F, " ", E).
    """))
    assert out == ["g ia_failed"]


# -- internal actions -----------------------------------------------------------------------------------
def test_random_of_a_list_picks_an_element():
    out = run_asl(asl("""
        !g.
        +!g <- .random([a,b,c], X); .print(X); .findall(Y, .random([a,b], Y, 5), L); .length(L, N); .print(N).
    """))
    assert out[0] in ("a", "b", "c")
    assert out[1] == "5"


def test_drop_all_desires_keeps_the_calling_intention():
    out = run_asl(asl("""
        !other.
        !g.
        +!g <- .drop_all_desires; .print(still_here).
        +!other <- .wait(100); .print(other).
    """), timeout=3)
    assert out == ["still_here"]


def test_remove_plan_with_a_source_removes_only_plans_from_that_source():
    out = run_asl(asl("""
        !g.
        +!g <- .add_plan({@p +!x <- .print(x)}, bob);
               .remove_plan(p, alice); .relevant_plans({+!x}, L1); .length(L1, N1); .print(N1);
               .remove_plan(p, bob); .relevant_plans({+!x}, L2); .length(L2, N2); .print(N2).
    """))
    assert out == ["1", "0"]


def test_desire_is_false_after_fail_goal():
    out = run_asl(asl("""
        !g.
        +!g <- !!go; .wait(50); .fail_goal(go); .wait(50);
               if (.desire(go)) { .print(still) } else { .print(gone) }.
        +!go <- .wait(1000).
        -!go <- .print(go_failed).
    """), timeout=5)
    assert out == ["go_failed", "gone"]


def test_suspended_gives_the_wait_reason_with_its_time():
    out = run_asl(asl("""
        !start.
        +!start <- !!go; .wait(50); .suspend(go); .suspended(go, R); .print(R).
        +!go <- .wait(500).
    """), timeout=3)
    assert out == ["wait(500)[time(500)]"]


def test_resume_lets_a_waiting_intention_go_on_waiting_and_runs_after_the_resumer():
    # resume.java: an intention suspended while waiting stays pending; a resumed one is queued behind
    out = run_asl(asl("""
        !start.
        +!start <- !!go; .wait(50); .suspend(go); .wait(500); .print(resuming); .resume(go); .print(resumed).
        +!go <- .wait(100); .print(go_done).
    """), timeout=5)
    assert out == ["resuming", "resumed", "go_done"]


def test_unknown_internal_action_posts_a_failure_event(caplog):
    out, warnings = run_asl_logged(asl("""
        !g.
        +!g <- .no_such_action(1).
        -!g[error(E)] <- .print(handled(E)).
    """), caplog)
    assert out == ["handled(ia_failed)"]


def test_relevant_plans_returns_renamed_copies_so_the_running_plan_survives():
    # the copies share no variable with the running plan: binding LP cannot build a cyclic term
    out = run_asl(asl("""
        !start.
        +!start <- .relevant_plans({+!start}, LP); .length(LP, N); .print(N);
                   LP = [P|_]; P = {@L +!T : C <- B}; .print(T).
    """))
    assert out == ["1", "start"]


def test_intention_describes_the_stack_as_jason():
    out = run_asl(asl("""
        !start.
        @top +!start <- !sub.
        +!sub <- .intention(I, S, [im(L, {+!G}, { Cur; _ }, _)|_], current); .print(S, " ", G, " ", Cur).
    """))
    assert out == ["running sub[source(self)] .intention(I,S,[im(L,{ +!G },{ Cur; _ },_)|_],current)"] or \
        out[0].startswith("running sub")


def test_intention_body_keeps_variables_not_values():
    """Jason's ``IntendedMeans.getAsTerm`` makes the body's variables anonymous instead of applying the
    unifier, so the same formula run twice with equal values gives two different terms (Jason's test
    manager counts each assert by this term)."""
    out = run_asl(asl("""
        !start.
        +!start <- X = 1; !check(X); !check(X); .count(seen(_), N); .print(N).
        +!check(_) : .intention(_, _, [im(_, _, { Cur; _ }, _)|_], current) <- +seen(Cur).
    """))
    assert out == ["2"]


def test_a_body_taken_from_a_plan_prints_without_braces():
    """Jason's PlanBody out of a plan is no term of its own: it prints without ``{ }``, so
    ``.substring(".send(", B, 0)`` holds for ``B`` of ``{@L +!T : C <- B}`` (Jason's own send test)."""
    out = run_asl(asl("""
        !g.
        +!go <- .send(bob, tell, x); .print(y).
        +!g <- .relevant_plans({+!go}, [{@L +!T : C <- B}]); .print(B);
               if (.substring(".send(", B, 0)) { .print(yes) }; X = { .print(a) }; .print(X).
    """))
    assert out == [".send(bob,tell,x); .print(y)", "yes", "{ .print(a) }"]


def test_univ_on_a_plan_and_running_its_body_formula_by_formula():
    """``Plan =.. [L, T, C, B]`` (Jason's Plan.getAsListOfTerms) and ``{H; R}`` taking the whole first
    formula, which runs when executed (Jason's demos/meta-programming, its output)."""
    out = run_asl(asl("""
        b(10).
        !start.
        @test +!g1 : b(10) <- ?b(X); .print(X); !g(X).
        +!g(X) <- .print(ok, X).
        +!start <- .relevant_plans({+!g1}, [Plan|_]); Plan =.. [L, T, C, B];
                   if (C) { .print("run ", T); !show_run(B) }.
        +!show_run({}) <- .print("end").
        +!show_run({H; R}) <- .print("command ", H); H; !show_run(R).
    """))
    assert [line for line in out if not line.startswith("command ?b(")] == [
        "run +!g1", "command .print(10)", "10", "command !g(10)", "ok10", "end"]
    assert len(out) == 7 and out[1].startswith("command ?b(")


def test_type_reports_jason_types():
    out = run_asl(asl("""
        !g.
        +!g <- .findall(T, .type(b, T), L1); .print(L1); .findall(T, .type([a], T), L2); .print(L2);
               .type(a[x], T3); .print(T3).
    """))
    assert out == ["[atom,literal,ground]", "[list,structure,ground]", "literal"]


def test_at_posts_the_event_later():
    out = run_asl(asl("""
        !g.
        +!g <- .at("now +100 ms", {+!later}); .print(now).
        +!later <- .print(later).
    """), timeout=3)
    assert out == ["now", "later"]


def test_create_and_kill_agent(tmp_path, monkeypatch):
    (tmp_path / "child.asl").write_text('!hi.\n+!hi <- .print(hello).\n')
    monkeypatch.chdir(tmp_path)
    out = run_mas({"parent": asl("""
        !g.
        +!g <- .create_agent(kid, "child.asl"); .wait(200); .kill_agent(kid); .all_names(L); .print(L).
    """)}, timeout=3)
    assert "[kid] hello" in out
    assert "[parent] [parent]" in out


def test_kill_agent_with_a_deadline_lets_the_agent_prepare_first(tmp_path, monkeypatch):
    """Jason's ``.kill_agent(Name, Deadline)`` (``LocalRuntimeServices.killAgent``): the agent gets
    ``+jag_shutting_down(Deadline)``, runs until the deadline, then is gone."""
    (tmp_path / "child.asl").write_text(
        "+jag_shutting_down(T) <- .print(closing(T)); !tick.\n"
        "+!tick <- .print(tick); .wait(100); !tick.\n")
    monkeypatch.chdir(tmp_path)
    out = run_mas({"parent": asl("""
        !g.
        +!g <- .create_agent(kid, "child.asl"); .kill_agent(kid, 250); .print(asked);
               .all_names(L); .print(L); .wait(500); .all_names(M); .print(M);
               .send(kid, tell, hi).
        -!g[error(E)] <- .print(E).
    """)}, timeout=3)
    assert out[:4] == ["[parent] asked", "[parent] [kid,parent]", "[kid] closing(250)", "[kid] tick"], out
    assert 2 <= out.count("[kid] tick") <= 3 and out[-2:] == ["[parent] [parent]", "[parent] receiver_not_found"], out


def test_a_name_in_use_gets_jasons_suffix_and_a_send_to_nobody_fails(tmp_path, monkeypatch):
    """Jason's ``getNewAgentName`` (``kid``, then ``kid_1``, ``kid_2``) and ``ReceiverNotFoundException``: a
    ``.send`` to an agent that does not exist (killed) fails with ``receiver_not_found``."""
    (tmp_path / "child.asl").write_text("")
    monkeypatch.chdir(tmp_path)
    out = run_mas({"parent": asl("""
        !g.
        +!g <- .create_agent(kid, "child.asl"); .create_agent(kid, "child.asl"); .create_agent(Kid, "child.asl");
               .all_names(L); .print(L, " ", Kid); .kill_agent(kid_1); .send(kid_1, tell, hi); .print(sent).
        -!g[error(E), agent_not_found(A), error_msg(M)] <- .print(E, " ", A); .print(M).
    """)}, timeout=3)
    assert out[:2] == ["[parent] [kid,kid_1,kid_2,parent] kid_2", "[parent] receiver_not_found kid_1"], out
    assert out[2].startswith("[parent] Receiver 'kid_1' does not exist! Could not send <"), out


def test_list_files_lists_matching_files_recursively(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "a.asl").write_text("")
    (tmp_path / "sub" / "b.asl").write_text("")
    (tmp_path / "c.txt").write_text("")
    out = run_asl(f'!g.\n+!g <- .list_files("{tmp_path}", ".*.asl", L); .length(L, N); .print(N).\n')
    assert out == ["2"]


# -- project files ------------------------------------------------------------------------------------
def test_mas2j_options_unescape_quotes():
    project = parse_mas2j('MAS m { agents: a [goals="g(\\"./x\\")"]; }')
    assert project.agents[0].options["goals"] == 'g("./x")'


def test_source_path_is_read_against_the_working_directory_and_includes_follow_it(tmp_path):
    (tmp_path / "proj").mkdir()
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "helper.asl").write_text("+!help <- .print(helped).\n")
    (tmp_path / "proj" / "a.asl").write_text('{ include("helper.asl") }\n!help.\n')
    (tmp_path / "proj" / "m.mas2j").write_text('MAS m { agents: a; aslSourcePath: "lib"; }')
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        project = parse_mas2j((tmp_path / "proj" / "m.mas2j").read_text(), "proj/m.mas2j")
        assert str(tmp_path / "lib") in project.source_dirs
        program = parse_program((tmp_path / "proj" / "a.asl").read_text(), "proj/a.asl",
                                source_path=tuple(project.source_dirs))
    finally:
        os.chdir(cwd)
    assert [str(p.trigger) for p in program.plans] == ["+!help"]


def test_jason_jar_include_is_found_along_the_source_path(tmp_path):
    (tmp_path / "inc").mkdir()
    (tmp_path / "inc" / "lib.asl").write_text("+!x <- .print(x).\n")
    program = parse_program('{ include("$jasonJar/test/jason/inc/lib.asl") }\n', str(tmp_path / "a.asl"),
                            source_path=(str(tmp_path / "inc"),))
    assert len(program.plans) == 1


def test_included_clauses_come_where_the_include_stands(tmp_path):
    (tmp_path / "lib.asl").write_text("-!g <- .print(library).\n")
    program = parse_program('{ include("lib.asl") }\n-!P <- .print(own).\n', str(tmp_path / "a.asl"))
    assert [str(p.trigger) for p in program.plans] == ["-!g", "-!P"]


def test_variable_plan_label_in_a_plan_term():
    out = run_asl(asl("""
        !g.
        @mine[test] +!g <- .relevant_plans({+!g}, [P]); P = {@L +!T : C <- B}; .print(L); .print(B).
    """))
    assert out[0].startswith("mine[")
    assert out[1].startswith(".relevant_plans")  # a body taken from a plan prints without braces (Jason)


# -- messages ------------------------------------------------------------------------------------------
def test_a_user_kqml_plan_does_not_swallow_other_messages():
    # Jason's kqmlPlans.asl comes after the user's plans: what the user's plan does not handle gets the
    # default semantics
    out = run_mas({
        "a": asl("""
            !g.
            +!g <- .send(b, tell, hello); .send(b, achieve, greet); .send(b, askOne, v(X), A); .print(A).
        """),
        "b": asl("""
            v(1).
            +!kqml_received(S, tell, C, _) <- .print(custom(C)).
            +!greet <- .print(greeted).
        """),
    }, timeout=5)
    assert "[b] custom(hello)" in out
    assert "[b] greeted" in out
    assert "[a] v(1)[source(b)]" in out


def test_directory_facilitator_register_search_subscribe():
    # jason.stdlib.df_register/df_search/df_subscribe: subscribers are told provider(Ag, Service)
    out = run_mas({
        "c": asl("""
            !start.
            +!start <- .df_subscribe("seller"); .wait(200); .df_search("seller", L); .print(L).
            +provider(A, S)[source(df)] <- .print(provider(A, S)).
        """),
        "s": asl("""
            !start.
            +!start <- .wait(50); .df_register("seller").
        """),
    }, timeout=5)
    assert "[c] provider(s,\"seller\")" in out
    assert "[c] [s]" in out


def test_sets_queues_and_maps_as_jason():
    # jason.stdlib.set/queue/map: mutable collections held by a variable; an unbound variable gets a new one
    out = run_asl(asl("""
        !t.
        +!t <- .set.add_all(S, [c, a, b, a]); .print(S); .length(S, N); .print(N);
               .queue.create(Q); .queue.add(Q, z); .queue.add(Q, y); .queue.remove(Q, H); .print(H, " ", Q);
               .queue.create(P, priority); .queue.add_all(P, [d, b, c]); .print(P);
               .map.create(M); .map.put(M, b, 2); .map.put(M, a, 1); .print(M);
               .map.get(M, zz, V, none); .print(V); .findall(K, .map.key(M, K), Ks); .print(Ks).
    """))
    assert out == ["{a,b,c}", "3", "z [y]", "[b,c,d]", "{a->1,b->2}", "none", "[a,b]"]


def test_clone_copies_beliefs_and_plans_but_not_goals():
    """Jason's ``.clone(Name)`` (demos/clone): the copy has the beliefs and plans of the moment it was
    made, runs none of the goals, and answers messages."""
    from tests.agentspeak.harness import run_mas
    main = """test(1).
        !start.
        +!start <- +a(40); .clone("bob"); .send(bob, tell, p(10)); .print(started).
        +p(X) : a(V) & test(T) <- .print(X, " : ", V + T).
    """
    assert run_mas({"main": main}) == ["[main] started", "[bob] 10 : 41"]


def test_stop_mas_with_a_delay_posts_jag_shutting_down_to_every_agent_and_runs_until_then():
    # RunLocalMAS.stopAgs: with a deadline, every agent gets +jag_shutting_down(Deadline) and runs
    # that long; .stopMAS itself succeeds (its caller goes on)
    out = run_mas({
        "a": "!s.\n+!s <- .stopMAS(3000); .print(goes_on).\n"
             "+jag_shutting_down(T) <- .print(a_down, T).\n",
        "b": "+jag_shutting_down(T) <- .wait(50); .print(b_packed, T / 1000).\n",
    }, timeout=20)  # (3 s: b's .wait(50) must end before the stop on a loaded machine too)
    assert sorted(out) == ["[a] a_down3000", "[a] goes_on", "[b] b_packed3"]


def test_a_select_option_rule_chooses_among_the_options():
    # Agent.selectOptionBB (Jason 3.3, demos/selectOptionBB): each option (plan x context solution) is
    # tested with select__option(Event, IntentionId, Plan, Unifier); the first that passes is taken
    out = run_asl(asl("""
        select__option(E, I, P, U) :- .print(I, " ", U) & P = {@L +!T : C <- B} & L =.. [_, _, As] & .member(kk, As).
        a(10). a(20). b(30).
        !g.
        +!g : a(X) <- .print(X).
        @pt[kk] +!g : b(X) <- .print(X).
    """))
    assert out == ["-1 [map(X,10)]", "-1 [map(X,20)]", "-1 [map(X,30)]", "30"]
