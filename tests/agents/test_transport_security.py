"""Isolation and access control with real Zenoh sessions: two MAS on one router do not see each other;
a router process links clients; an access-control rule keyed on a user name denies one key."""
from __future__ import annotations

import argparse
import shutil
import signal
import subprocess

import pytest

from agents.router import DEFAULT_LISTEN, add_router_parser
from agents.transport import Envelope, Inbox, ZenohOptions, ZenohTransport, free_port, loopback_endpoint
from tests.agents.transport_fixtures import poll, probe, router, unique_mas


@pytest.fixture(scope="module")
def router_endpoint():
    child = router(loopback_endpoint())
    yield child.endpoints[0]
    assert child.stop(signum=signal.SIGTERM) == 0  # the router's clean shutdown path


def client(mas: str, endpoint: str) -> ZenohTransport:
    return ZenohTransport(mas, ZenohOptions(mode="client", connect=(endpoint,))).open()


def test_router_cli_defaults_to_loopback():
    parser = argparse.ArgumentParser()
    add_router_parser(parser.add_subparsers())
    args = parser.parse_args(["router"])
    assert DEFAULT_LISTEN.startswith("tcp/127.0.0.1:") and args.listen is None and args.func
    args = parser.parse_args(["router", "--listen", "tcp/127.0.0.1:1", "--connect", "tcp/127.0.0.1:2"])
    assert (args.listen, args.connect) == (["tcp/127.0.0.1:1"], ["tcp/127.0.0.1:2"])


def test_clients_of_a_router_process_exchange_messages_and_presence(router_endpoint):
    mas = unique_mas()
    one, two = client(mas, router_endpoint), client(mas, router_endpoint)
    try:
        inbox = Inbox()
        one.register("alice", Inbox())
        two.register("bob", inbox)
        assert one.wait_for_agents(["alice", "bob"], timeout=10)
        assert one.send(Envelope(mas, "alice", ("bob",), "tell", "via_router")) == ()
        assert inbox.get(timeout=10).content == "via_router"
    finally:
        two.close()
    assert one.wait_for_agents(["bob"], timeout=10, alive=False)
    one.close()


def test_two_mas_on_one_router_do_not_see_each_other(router_endpoint):
    red_mas, blue_mas = unique_mas("red"), unique_mas("blue")
    red, red_sender, blue = (client(red_mas, router_endpoint), client(red_mas, router_endpoint),
                             client(blue_mas, router_endpoint))
    try:
        red_bob, blue_bob = Inbox(), Inbox()
        red.register("bob", red_bob)
        blue.register("bob", blue_bob)
        blue.register("carol", Inbox())
        red_sender.register("alice", Inbox())
        assert red_sender.wait_for_agents(["bob", "alice"], timeout=10)
        assert blue.wait_for_agents(["bob", "carol"], timeout=10)
        assert red_sender.send(Envelope(red_mas, "alice", ("bob", "carol"), "tell", "red_only")) == ("carol",)
        assert red_bob.get(timeout=10).content == "red_only"
        red_sender.publish_control("stop")
        assert blue.alive_agents() == {"bob", "carol"} and red_sender.alive_agents() == {"bob", "alice"}
        # blue's bob heard nothing: a message sent after red's to blue's bob arrives first.
        blue.send(Envelope(blue_mas, "carol", ("bob",), "tell", "blue_only"))
        assert blue_bob.get(timeout=10).content == "blue_only" and len(blue_bob) == 0
    finally:
        for transport in (red, red_sender, blue):
            transport.close()


def test_access_control_denies_a_user_the_stop_command(tmp_path):
    """Deployment rule from docs/deployment.md: agents that join as user 'joiner' may talk but may
    not stop the MAS; the operator may."""
    mas = unique_mas()
    dictionary = tmp_path / "users.txt"
    dictionary.write_text("operator:op-secret\njoiner:join-secret\n")
    hub_file = tmp_path / "hub.json5"
    hub_file.write_text(f"""{{
      transport: {{ auth: {{ usrpwd: {{ user: "hub", password: "hub-secret", dictionary_file: "{dictionary}" }} }} }},
      access_control: {{
        enabled: true, default_permission: "allow",
        rules: [{{ id: "no_stop", messages: ["put"], flows: ["ingress"], permission: "deny",
                   key_exprs: ["faultmas/*/control"] }}],
        subjects: [{{ id: "joiners", usernames: ["joiner"] }}],
        policies: [{{ rules: ["no_stop"], subjects: ["joiners"] }}],
      }},
    }}""")
    endpoint = f"tcp/127.0.0.1:{free_port()}"

    def user_file(name: str, password: str):
        path = tmp_path / f"{name}.json5"
        path.write_text(f'{{ transport: {{ auth: {{ usrpwd: {{ user: "{name}", password: "{password}" }} }} }} }}')
        return path

    hub = ZenohTransport(mas, ZenohOptions(listen=(endpoint,), config_file=hub_file)).open()
    controls, inbox = [], Inbox()
    hub.on_control(controls.append)
    hub.register("base", inbox)
    joiner = probe("echo", mas, "joiner", [endpoint], "--config", str(user_file("joiner", "join-secret")))
    operator = probe("echo", mas, "operator", [endpoint], "--config", str(user_file("operator", "op-secret")))
    intruder = probe("echo", mas, "intruder", [endpoint], "--config", str(user_file("joiner", "wrong")))
    try:
        assert hub.wait_for_agents(["joiner", "operator"], timeout=30)
        # The joiner's stop is denied at the hub, its speech acts are not.
        hub.send(Envelope(mas, "base", ("joiner",), "tell", "hello"))
        assert inbox.get(timeout=10).sender == "joiner"
        joiner_stop = ZenohTransport(mas, ZenohOptions(connect=(endpoint,),
                                                       config_file=user_file("joiner", "join-secret"))).open()
        joiner_stop.register("joiner2", Inbox())
        assert hub.wait_for_agents(["joiner2"], timeout=10)
        joiner_stop.publish_control("stop", by="joiner2")
        hub.send(Envelope(mas, "base", ("joiner",), "tell", "after_joiner_stop"))
        assert inbox.get(timeout=10).content == "after_joiner_stop"  # its stop would have come before
        assert controls == []
        operator_stop = ZenohTransport(mas, ZenohOptions(connect=(endpoint,),
                                                         config_file=user_file("operator", "op-secret"))).open()
        operator_stop.publish_control("stop", by="operator")
        assert poll(lambda: controls, timeout=10)
        assert controls == [{"command": "stop", "by": "operator"}]
        assert "intruder" not in hub.alive_agents()  # wrong password: no session with the hub
        joiner_stop.close()
        operator_stop.close()
    finally:
        for child in (joiner, operator, intruder):
            child.stop()
        hub.close()


def make_certificates(directory) -> dict[str, str]:
    """A throw-away CA and a server certificate for 'localhost' (with the openssl command)."""
    run = lambda *args: subprocess.run(["openssl", *args], cwd=directory, check=True,  # noqa: E731
                                       capture_output=True)
    run("req", "-x509", "-newkey", "rsa:2048", "-nodes", "-keyout", "ca.key", "-out", "ca.pem", "-days", "2",
        "-subj", "/CN=faultmas-test-ca")
    run("req", "-newkey", "rsa:2048", "-nodes", "-keyout", "hub.key", "-out", "hub.csr", "-subj", "/CN=hub")
    (directory / "san.ext").write_text("subjectAltName=DNS:localhost,IP:127.0.0.1\n")
    run("x509", "-req", "-in", "hub.csr", "-CA", "ca.pem", "-CAkey", "ca.key", "-CAcreateserial",
        "-out", "hub.pem", "-days", "2", "-extfile", "san.ext")
    return {name: str(directory / name) for name in ("ca.pem", "hub.pem", "hub.key")}


@pytest.mark.skipif(shutil.which("openssl") is None, reason="needs the openssl command to make certificates")
def test_tls_link_carries_messages_and_refuses_a_peer_without_the_ca(tmp_path):
    """The TLS set-up of docs/deployment.md: the hub listens on tls/ with its certificate, agents
    connect with the CA; a peer that does not trust the CA gets no link."""
    files = make_certificates(tmp_path)
    hub_file, agent_file = tmp_path / "hub.json5", tmp_path / "agent.json5"
    hub_file.write_text(f'{{ transport: {{ link: {{ tls: {{ listen_certificate: "{files["hub.pem"]}", '
                        f'listen_private_key: "{files["hub.key"]}" }} }} }} }}')
    agent_file.write_text(f'{{ transport: {{ link: {{ tls: {{ root_ca_certificate: "{files["ca.pem"]}" }} }} }} }}')
    endpoint, mas = f"tls/localhost:{free_port()}", unique_mas()
    with ZenohTransport(mas, ZenohOptions(listen=(endpoint,), config_file=hub_file)) as hub, \
            ZenohTransport(mas, ZenohOptions(connect=(endpoint,), config_file=agent_file)) as agent, \
            ZenohTransport(mas, ZenohOptions(connect=(endpoint,))) as stranger:
        inbox = Inbox()
        hub.register("bob", inbox)
        agent.register("alice", Inbox())
        assert agent.wait_for_agents(["bob"], timeout=10)
        assert agent.send(Envelope(mas, "alice", ("bob",), "tell", "over_tls")) == ()
        assert inbox.get(timeout=10).content == "over_tls"
        assert [link.dst.startswith("tls/") for link in agent.session.info.links()] == [True]
        assert not stranger.wait_for_agents(["bob"], timeout=1.0)
        assert stranger.send(Envelope(mas, "alice", ("bob",), "tell", "x")) == ("bob",)
