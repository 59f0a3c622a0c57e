"""Agents made at run time (``.create_agent``, ``.clone``) are agents of the whole MAS with ``--processes``, as a
launched agent is: reachable by name from every process, in every ``.all_names``, found by every ``.df_search``,
allowed what members are (``achieve``, ``.stopMAS``); ``.kill_agent`` removes them everywhere, after which a
``.send`` to them fails as Jason's does (``receiver_not_found``). In the secure profile ``.create_agent`` is
refused, saying why. Real ``faultmas mas run`` processes over Zenoh on loopback, against the in-process run."""
from __future__ import annotations

from agents.mas_cli import build_local_mas
from agents.transport import Envelope, LocalBus, LocalTransport
from agents.transport.identity import generate_keys
from agents.zenoh_arch import TransportBridge
from agentspeak.communication import Message
from agentspeak.mas2j import load_mas2j
from agentspeak.runtime import LocalRuntime
from agentspeak.terms import Literal
from tests.agents.distributed_fixtures import mas_run, write_files
from tests.agents.transport_fixtures import unique_mas

# maker (one process) makes `asker` (taken by the asker of another process: `asker_1`), clones itself as twin
# and makes worker, which registers and asks asker to achieve `ready`; asker asks worker and twin, lists the
# names and searches the DF, kills twin itself (an agent of another process), has maker kill worker, waits until
# both are gone from its names, searches again and sends to worker: the send fails; asker_1 (made at run time)
# stops the MAS.
MADE = {
    "made.mas2j": "MAS made { agents: maker; asker; }\n",
    "maker.asl": r'''
role(maker).
!start.
+!start <- .create_agent(Asker, "clash.asl"); .print(clash(Asker)); .clone(twin); .create_agent(worker, "worker.asl").
+!kill(W)[source(S)] <- .kill_agent(W); .send(S, tell, killed(W)).
''',
    "clash.asl": "+!stop <- .stopMAS.\n",
    "worker.asl": '!start.\n+!start <- .df_register("echo"); .send(asker, achieve, ready).\n+?ping(X) <- X = pong.\n',
    "asker.asl": r'''
+!ready[source(W)] <-
    .send(W, askOne, ping(X), A, 10000); .print(answer(A));
    .send(twin, askOne, role(R), T, 10000); .print(twin(T));
    .all_names(L); .print(names(L));
    .df_search("echo", P); .print(providers(P));
    .kill_agent(twin);
    .send(maker, achieve, kill(W)).
+killed(W)[source(maker)] <- !gone(W).
+!gone(W) <- .all_names(L);
    if (.member(W, L) | .member(twin, L)) { .wait(50); !gone(W) }
    else { .print(left(L)); .df_search("echo", P); .print(after(P)); .send(W, tell, hi); .print(sent_anyway); .stopMAS }.
-!gone(W)[error(E), agent_not_found(A)] <- .print(send_failed(E, A)); .send(asker_1, achieve, stop).
''',
}

EXPECTED = ['[maker] clash("asker_1")', "[asker] answer(ping(pong)[source(worker)])",
            "[asker] twin(role(maker)[source(twin)])", "[asker] names([asker,asker_1,maker,twin,worker])",
            "[asker] providers([worker])", "[asker] left([asker,asker_1,maker])", "[asker] after([])",
            "[asker] send_failed(receiver_not_found,worker)"]


def test_made_agents_are_agents_of_every_process_until_killed(tmp_path):
    write_files(tmp_path, MADE)
    here: list[str] = []
    runtime = build_local_mas(load_mas2j(str(tmp_path / "made.mas2j")), printer=lambda n, t: here.append(f"[{n}] {t}"))
    runtime.source_dirs = [str(tmp_path)]
    assert runtime.run(timeout=30) == "stopped"
    assert here == EXPECTED
    run = mas_run(tmp_path / "made.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish(90) == 0, run.err[-20:]
    # (two processes: their lines are relayed by two threads, so only each agent's own order is fixed)
    assert [line for line in run.out if line.startswith("[maker]")] == EXPECTED[:1], (run.out, run.err[-20:])
    assert [line for line in run.out if line.startswith("[asker]")] == EXPECTED[1:], (run.out, run.err[-20:])
    assert not [line for line in run.err if "dropped" in line and "unknown agent 'worker'" not in line], run.err[-20:]


def test_create_agent_is_refused_in_the_secure_profile_saying_why(tmp_path):
    write_files(tmp_path, {
        "s.mas2j": 'MAS s { agents: maker [key="keys"]; }\n', "worker.asl": "",
        "maker.asl": '!start.\n+!start <- .create_agent(worker, "worker.asl").\n'
                     '-!start[error(E), error_msg(M)] <- .print(E); .print(M); .stopMAS.\n'})
    generate_keys(tmp_path / "keys", ["maker"])
    run = mas_run(tmp_path / "s.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish(90) == 0, run.err[-20:]
    assert run.out[0] == "[maker] secure_profile", run.out
    assert "cannot create agent worker in the secure profile" in run.out[1] and "key=" in run.out[1], run.out


def test_members_are_the_projects_agents_and_those_they_made(tmp_path, monkeypatch):
    """The bridge's trust (two 'processes' on the in-memory bus): an agent made by a member may make others act
    and stop the MAS, and stays a member after it is killed (its last messages may come after it is gone); one
    made by a stranger, or a stranger, may not; a name taken in the other process gets Jason's suffix."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "kid.asl").write_text("!go.\n+!go <- .send(b, achieve, hello).\n")
    mas, bus = unique_mas("made"), LocalBus()
    out: list[str] = []
    here, there = (LocalRuntime(printer=lambda n, t: out.append(f"[{n}] {t}")) for _ in range(2))
    here.add_agent("a", '+!make <- .create_agent(kid, "kid.asl"); .create_agent(b, "kid.asl").\n')
    there.add_agent("b", "+!hello[source(S)] <- .print(hello(S)).\n")
    transports = [LocalTransport(mas, bus).open() for _ in range(2)]
    bridges = [TransportBridge(runtime, transport, declared=["a", "b"], members=["a", "b"]).attach()
               for runtime, transport in zip((here, there), transports)]
    here.route(Message("a", "a", "achieve", Literal("make")))
    here.run(timeout=2)
    assert sorted(here.agents) == ["a", "b_1", "kid"] and transports[1].creator_of("b_1") == "a"
    there_bridge = bridges[1]
    assert there_bridge.is_member("kid") and there_bridge.may_tell_how("kid")
    there.run(timeout=2)
    assert sorted(out) == ["[b] hello(b_1)", "[b] hello(kid)"]  # achieve: only from members
    here.kill_agent("kid")
    assert "kid" not in transports[1].alive_agents() and there_bridge.is_member("kid")
    transports[0].register("stranger", lambda envelope: None)
    transports[0].register("minion", lambda envelope: None, creator="stranger")
    assert transports[1].creator_of("minion") == "stranger"
    assert not any(there_bridge.is_member(name) for name in ("stranger", "minion", "nobody"))
    transports[0].send(Envelope(mas, "stranger", ("b",), "achieve", "hello"))
    assert transports[1].dropped["not_a_member"] == 1
    for bridge in bridges:
        bridge.detach()
    for transport in transports:
        transport.close()


def test_a_project_agent_killed_in_another_process_leaves_every_all_names(tmp_path, monkeypatch):
    """As in Jason, ``.all_names`` lists the agents there are: a project's agent before its process is seen (Jason
    creates all before any runs), not after ``.kill_agent`` removed it, wherever that happened; its name is then
    free for ``.create_agent`` again."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "kid.asl").write_text("")
    mas, bus = unique_mas("names"), LocalBus()
    here, there = LocalRuntime(), LocalRuntime()
    here.add_agent("a", "")
    there.add_agent("b", "")
    transports = [LocalTransport(mas, bus).open() for _ in range(2)]
    bridges = [TransportBridge(runtime, transport, declared=["a", "b", "c"], members=["a", "b", "c"]).attach()
               for runtime, transport in zip((here, there), transports)]
    assert transports[0].wait_for_agents(["b"], timeout=5)
    assert bridges[0].all_names() == ["a", "b", "c"]          # c: of the project, not started yet
    there.kill_agent("b")
    assert transports[0].wait_for_agents(["b"], timeout=5, alive=False)
    assert bridges[0].all_names() == ["a", "c"] and bridges[1].all_names() == ["a", "c"]
    assert here.create_agent("b", "kid.asl") == "b" and here.create_agent("c", "kid.asl") == "c_1"
    for bridge in bridges:
        bridge.detach()
    for transport in transports:
        transport.close()


SHUTDOWN = {
    "shut.mas2j": "MAS shut { agents: killer; victim; bystander; }\n",
    "killer.asl": "!start.\n+!start <- .kill_agent(victim, 300); .wait(1000); .all_names(L); .print(L); .stopMAS(300).\n",
    "victim.asl": "+jag_shutting_down(T) <- .print(closing(T)).\n",
    "bystander.asl": "+jag_shutting_down(T) <- .print(shutting(T)).\n",
}


def test_kill_agent_and_stop_mas_with_a_deadline_warn_agents_of_other_processes(tmp_path):
    """Jason's ``+jag_shutting_down(T)`` reaches an agent of another process: killed with a deadline
    (``.kill_agent(victim, 300)``), or stopped with the MAS (``.stopMAS(300)`` from another process)."""
    write_files(tmp_path, SHUTDOWN)
    run = mas_run(tmp_path / "shut.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish(90) == 0, run.err[-20:]
    assert sorted(run.out) == ["[bystander] shutting(300)", "[killer] [bystander,killer]",
                               "[victim] closing(300)"], (run.out, run.err[-20:])



# Two agents in two processes make an agent named after the variable `Kid` (so `kid`, else the next free `kid_N`) at
# the same moment, 20 rounds: each round's creators must get two different names, each name must be one agent (one
# `up` line), and both processes' `.all_names` must agree at the end. A round starts when an agent has told the other
# it is at that round and heard the same from it (a barrier of two messages, a millisecond or so apart).
ROUNDS = 20
RACER = r'''
!round(1).
+!round(N) : N > %d <- +finishing; .send(PEER, tell, done); !finish.
+!round(N) <- +mine(N); .send(PEER, tell, at(N)); !maybe(N).
+at(N)[source(_)] : mine(N) <- !maybe(N).
@maybe[atomic] +!maybe(N) : mine(N) & at(N)[source(_)] & not made(N) <- +made(N); !make(N).
+!maybe(N).
+!make(N) <- .create_agent(Kid, "kid.asl"); .print(made(N, Kid)); !round(N + 1).
+done[source(_)] : finishing <- !finish.
@finish[atomic] +!finish : finishing & done[source(_)] & not finished <-
    +finished; .all_names(L); .print(names(L)); .send(PEER, tell, printed); !stop.
+!finish.
+printed[source(_)] : finished <- !stop.
@stop[atomic] +!stop : .my_name(racer1) & finished & printed[source(_)] & not stopping <- +stopping; .stopMAS.
+!stop.
''' % ROUNDS
RACE = {"race.mas2j": "MAS race { agents: racer1; racer2; }\n", "kid.asl": "!up.\n+!up <- .print(up).\n",
        "racer1.asl": RACER.replace("PEER", "racer2"), "racer2.asl": RACER.replace("PEER", "racer1")}


def test_two_processes_making_one_name_at_once_get_two_names(tmp_path):
    """Issue 22: a name made at run time is unique across processes even when two make it at the same moment (the
    loser gets the next free name, as in Jason); before, both processes got it in about one round of two."""
    write_files(tmp_path, RACE)
    run = mas_run(tmp_path / "race.mas2j", "--processes", "--timeout", "60", cwd=tmp_path)
    assert run.finish(90) == 0, run.err[-20:]
    made: dict[int, list[str]] = {}
    for line in run.out:
        if "] made(" in line:
            round_, name = line.split("made(", 1)[1].rstrip(")").split(",")
            made.setdefault(int(round_), []).append(name.strip('"'))
    assert sorted(made) == list(range(1, ROUNDS + 1)) and all(len(names) == 2 for names in made.values()), run.out
    clashes = {round_: names for round_, names in made.items() if names[0] == names[1]}
    ups = [line.split("]", 1)[0][1:] for line in run.out if line.endswith("] up")]
    twice = sorted({name for name in ups if ups.count(name) > 1})
    assert not clashes and not twice, f"{len(clashes)} of {ROUNDS} rounds gave one name twice: {clashes}; " \
                                      f"agents that ran twice: {twice}"
    assert sorted(ups) == sorted(name for pair in made.values() for name in pair)
    names = [line.split("names(", 1)[1] for line in run.out if "] names(" in line]
    expected = f"[{','.join(sorted(['racer1', 'racer2', *ups]))}])"
    assert names == [expected, expected], (names, expected)
