"""Issue 22, identity and access: in the secure profile (per-agent Ed25519 keys listed in the project) a
real outsider process with its own Zenoh session cannot tell, achieve, tellHow, ask or stop — not under
its own name, not under a member's, not by replaying or altering a member's signed message — and each
attempt is refused with a reason; a member in another process (``faultmas agent run``) tells, makes bob
act and gets an answer."""
from __future__ import annotations

import os
import queue
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
from agents.transport.envelope import BadMessage, Envelope
from agents.transport.identity import (Identity, IdentityError, generate_keys, project_identity,
                                       project_key_files)
from agents.zenoh_arch import TransportBridge
from agentspeak.mas2j import load_mas2j
from agentspeak.runtime import LocalRuntime
from tests.agents.transport_fixtures import poll, unique_mas

REPO = Path(__file__).resolve().parents[2]
BOB = "secret(42).\n+!act[source(S)] <- +did(act, S).\n"
ALICE = ("!start.\n+!start <- .send(bob, tell, hello_from(alice)); .send(bob, achieve, act);\n"
         "    .send(bob, askOne, secret(X), Answer); .print(\"answer \", Answer).\n")


def _project(tmp_path: Path, mas: str) -> Path:
    generate_keys(tmp_path / "keys", ["alice", "bob"])
    generate_keys(tmp_path / "outside", ["mallory"])
    (tmp_path / "alice.asl").write_text(ALICE)
    (tmp_path / "bob.asl").write_text(BOB)
    project = tmp_path / "team.mas2j"
    project.write_text(f'MAS {mas} {{ agents: alice alice.asl [key="keys"]; bob bob.asl [key="keys/bob.pub"]; }}\n')
    return project


def _child_env() -> dict:
    return dict(os.environ, PYTHONPATH=str(REPO), PYTHONUNBUFFERED="1")


def _lines(stream, into: queue.Queue) -> None:
    for line in stream:
        into.put(line)


def test_an_outsider_process_cannot_tell_achieve_teach_ask_or_stop_in_the_secure_profile(tmp_path):
    mas, endpoint = unique_mas(), loopback_endpoint()
    project_file = _project(tmp_path, mas)
    project = load_mas2j(str(project_file))
    runtime = LocalRuntime(printer=lambda name, text: None)
    runtime.add_agent("bob", BOB)
    identity = project_identity(project, ["bob"])
    with ZenohTransport(mas, ZenohOptions(listen=(endpoint,)), identity=identity) as transport:
        bridge = TransportBridge(runtime, transport, declared=project.agent_names(),
                                 members=project.agent_names()).attach()
        outsider = subprocess.Popen([sys.executable, "-m", "tests.hardening.secure_outsider", "--mas", mas,
                                     "--connect", endpoint, "--key", str(tmp_path / "outside" / "mallory.key")],
                                    cwd=REPO, env=_child_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                    text=True)
        said: queue.Queue = queue.Queue()
        threading.Thread(target=_lines, args=(outsider.stdout, said), daemon=True).start()
        alice = None
        try:
            while alice is None:  # the MAS runs while the outsider gets ready, then alice starts
                assert bridge.run(timeout=0.3) == "timeout"
                try:
                    line = said.get_nowait()
                except queue.Empty:
                    assert outsider.poll() is None, outsider.stderr.read()[-2000:]
                    continue
                assert line.strip() == "READY", line
                alice = subprocess.Popen([sys.executable, "-m", "agents", "agent", "run", "alice.asl", "--name",
                                          "alice", "--mas", mas, "--project", str(project_file), "--connect",
                                          endpoint, "--wait-for-peers", "30", "--timeout", "90"],
                                         cwd=tmp_path, env=_child_env(), stdout=subprocess.PIPE,
                                         stderr=subprocess.PIPE, text=True)
            while outsider.poll() is None:  # until the outsider has sent everything
                assert bridge.run(timeout=0.5) == "timeout", "the MAS stopped: an outsider's stop was obeyed"
            assert bridge.run(timeout=2.0) == "timeout"
            assert outsider.returncode == 0, outsider.stderr.read()[-2000:]
            assert said.get(timeout=5).strip() == "SENT"
        finally:
            bridge.detach()
            outsider.kill()
            if alice is not None:
                alice.terminate()
        alice_out, alice_err = alice.communicate(timeout=30)
    beliefs = {str(b) for b in runtime.agents["bob"].bb.literals()}
    assert "hello_from(alice)[source(alice)]" in beliefs, (beliefs, alice_err[-2000:])  # a member's tell
    assert "did(act,alice)[source(self)]" in beliefs                                    # a member's goal
    assert "answer secret(42)" in alice_out, alice_err[-2000:]                          # a member's question
    assert not any("evil" in b or "did(act,mallory)" in b for b in beliefs), beliefs
    assert sum("did(act" in b for b in beliefs) == 1, beliefs                           # the replay did not act
    assert not any("evil" in str(plan) for plan in runtime.agents["bob"].plans.plans), "a planted plan"
    assert dict(transport.dropped) == {
        "unsigned": 2,          # a stranger's tell, a goal under alice's name, both without a signature
        "unknown_sender": 4 + 1,  # mallory's own signed tell, achieve, tellHow, askOne, and its signed stop
        "bad_signature": 2,     # from alice signed with mallory's key; alice's message with its content altered
        "replayed": 1,          # alice's message put again
        "not_a_member": 2,      # an unsigned stop naming alice (the name is a mere claim), the 'launcher' without token
    }


def test_a_project_half_in_the_secure_profile_and_a_wrong_private_key_are_refused_with_the_file(tmp_path):
    generate_keys(tmp_path / "keys", ["alice", "bob"])
    (tmp_path / "a.asl").write_text("")
    half = tmp_path / "half.mas2j"
    half.write_text('MAS m { agents: alice a.asl [key="keys"]; bob a.asl; }\n')
    with pytest.raises(IdentityError, match="bob have no key= option"):
        project_key_files(load_mas2j(str(half)))
    full = tmp_path / "full.mas2j"
    full.write_text('MAS m { agents: alice a.asl [key="keys"]; bob a.asl [key="keys"]; }\n')
    with pytest.raises(IdentityError, match="does not match the public key"):
        project_identity(load_mas2j(str(full)), ["alice"], tmp_path / "keys" / "bob.key")
    with pytest.raises(IdentityError, match="nokey.key: cannot read the key"):
        project_identity(load_mas2j(str(full)), ["alice"], tmp_path / "nokey.key")


def test_replay_memory_stays_bounded_and_refuses_what_it_forgot(tmp_path):
    generate_keys(tmp_path, ["alice"])
    identity = Identity.from_files({"alice": tmp_path / "alice.pub"}, {"alice": tmp_path / "alice.key"})
    envelope = Envelope("m", "alice", ("bob",), "tell", "x")
    sealed_seq = identity.open(identity.seal("alice", envelope.encode()), lambda doc: "alice")[1]
    seqs = [sealed_seq + i for i in range(10_000)]  # what alice's next 10,000 messages carry
    for seq in seqs:
        identity.check_fresh("alice", "bob", seq)
    assert sum(len(seen) for seen in identity.replays._seen.values()) <= 4097
    for seq in (seqs[0], seqs[-1]):  # forgotten long ago, and remembered
        with pytest.raises(BadMessage, match="replayed"):
            identity.check_fresh("alice", "bob", seq)
    identity.check_fresh("alice", "carol", seqs[0])  # the same message to another receiver is its own
    with pytest.raises(BadMessage, match="stale"):  # a message from before the receiver's memory began
        identity.check_fresh("alice", "dave", seqs[0] - 60_000_000)


def test_mas_run_processes_in_the_secure_profile_talks_and_a_missing_private_key_is_named(tmp_path):
    """The user's way: keys made by ``faultmas keys generate``, listed in the project, ``mas run --processes``."""
    from tests.agents.distributed_fixtures import mas_run, write_files

    write_files(tmp_path, {
        "alice.asl": '!start.\n+!start <- .send(bob, askOne, secret(X), A); .print("answer ", A); .stopMAS.\n',
        "bob.asl": "secret(42).\n",
        "team.mas2j": 'MAS secure { agents: alice alice.asl [key="keys"]; bob bob.asl [key="keys"]; }\n'})
    generate = subprocess.run([sys.executable, "-m", "agents", "keys", "generate", "keys", "alice", "bob"],
                              cwd=tmp_path, env=_child_env(), capture_output=True, text=True, timeout=60)
    assert generate.returncode == 0, generate.stderr
    run = mas_run(tmp_path / "team.mas2j", "--processes", "--timeout", "120", cwd=tmp_path)
    assert run.finish(timeout=150) == 0, run.err[-20:]
    assert "[alice] answer secret(42)[source(bob)]" in run.out
    assert not any("dropped" in line for line in run.err), run.err  # nothing refused between members
    (tmp_path / "keys" / "bob.key").unlink()  # bob's process refuses to start, naming the file
    run = mas_run(tmp_path / "team.mas2j", "--processes", "--timeout", "120", cwd=tmp_path)
    try:
        assert poll(lambda: any("bob.key: cannot read the key" in line for line in run.err), 60), run.err[-20:]
        assert poll(lambda: any("bob died" in line for line in run.err), 60), run.err[-20:]
        assert not any("answer" in line for line in run.out), run.out      # alice got no answer from bob
    finally:     # alice, idle, would wait for the --timeout: not waited out (it proves nothing more)
        run.stop()


def test_a_forged_agent_status_is_refused_in_the_secure_profile(tmp_path):
    """A status says an agent is idle and what it sent and received: ``mas run`` ends when all are idle, so a
    forged 'idle' could end the MAS while its agents work. In the secure profile a status is signed by the
    agent it is about; an unsigned one, or one signed by another key, is refused with a reason, whether it
    is put on the status key or given as an answer to a status query."""
    import time

    from agents.transport.keys import status_key
    from agents.transport.status import AgentStatus

    generate_keys(tmp_path / "keys", ["alice", "bob"])
    generate_keys(tmp_path / "outside", ["mallory"])
    public = {n: tmp_path / "keys" / f"{n}.pub" for n in ("alice", "bob")}
    alice_identity = Identity.from_files(public, {"alice": tmp_path / "keys" / "alice.key"})
    observer_identity = Identity.from_files(public)
    from agents.transport.identity import load_private_key
    mallory_key = load_private_key(tmp_path / "outside" / "mallory.key")
    as_bob = Identity({"bob": mallory_key.public_key()}, {"bob": mallory_key})  # bob's name, mallory's key
    mas, endpoint = unique_mas(), loopback_endpoint()
    forged = AgentStatus("bob", False, 0, 0).encode()
    seen: list = []
    with ZenohTransport(mas, ZenohOptions(listen=(endpoint,)), identity=observer_identity) as observer, \
            ZenohTransport(mas, ZenohOptions(mode="client", connect=(endpoint,)), identity=alice_identity) as alice, \
            ZenohTransport(mas, ZenohOptions(mode="client", connect=(endpoint,))) as outsider:
        observer.on_status(seen.append)
        alice.register("alice", lambda envelope: None)
        assert observer.wait_for_agents(["alice"], timeout=30)
        answer = outsider.session.declare_queryable(  # an outsider answering status queries for bob
            status_key(mas, "bob"), lambda query: query.reply(status_key(mas, "bob"), forged))
        time.sleep(0.5)
        alice.publish_status("alice", busy=True)                                  # signed by alice
        outsider.session.put(status_key(mas, "bob"), forged)                      # unsigned
        outsider.session.put(status_key(mas, "bob"), as_bob.seal("bob", forged))  # bob's name, another key
        deadline = time.monotonic() + 20
        while (not seen or sum(observer.dropped.values()) < 2) and time.monotonic() < deadline:
            time.sleep(0.1)
        collected = observer.collect_status(timeout=3.0)
        answer.undeclare()
    assert [(s.agent, s.busy) for s in seen] == [("alice", True)]
    assert [(s.agent, s.busy) for s in collected] == [("alice", True)]   # alice's answer, signed; not bob's
    assert dict(observer.dropped) == {"unsigned": 2, "bad_signature": 1}   # the put and the query's answer
