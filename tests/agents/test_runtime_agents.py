"""Agents made at run time (``.create_agent``, ``.clone``) are agents of the whole MAS with ``--processes``, as a
launched agent is: reachable by name from every process, in every ``.all_names``, found by every ``.df_search``,
allowed what members are (``achieve``, ``.stopMAS``); ``.kill_agent`` removes them everywhere, after which a
``.send`` to them fails as Jason's does (``receiver_not_found``). In the secure profile ``.create_agent`` is
refused, saying why. Real ``faultmas mas run`` processes over Zenoh on loopback, against the in-process run."""
from __future__ import annotations

from agents.mas_cli import build_local_mas
from agents.transport.identity import generate_keys
from agentspeak.mas2j import load_mas2j
from tests.agents.distributed_fixtures import mas_run, write_files

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
+?role(R) <- ?role(R).
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
            "[asker] providers([worker])", "[asker] left([asker,asker_1,maker])", "[asker] after([])", "[asker] send_failed(receiver_not_found,worker)"]


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
