"""Who really sent a message: per-agent Ed25519 keys, signed envelopes, replay refusal (the secure profile).

Why signed envelopes (and not only TLS with per-agent certificates): a TLS link proves which *process*
is at the other end of one hop; behind a router, a receiver still reads a ``from`` that the router did
not check. A signature over the envelope's bytes is checked by the receiver itself, end to end, through
any number of routers and on any transport (Zenoh, in-memory), and a router's access-control rules are
not needed for it. TLS stays useful beside it (confidentiality, keeping outsiders off the links:
docs/deployment.md); this module answers "who said this", which TLS alone cannot.

Keys: each agent has an Ed25519 key pair. The project lists every member's *public* key (option
``key="keys/alice.pub"`` of its declaration in the ``.mas2j``; a directory means ``<dir>/<name>.pub``);
the private key (``alice.key`` beside it, or ``--identity FILE``) is only on the agent's own host.
Files are PEM, as ``openssl genpkey -algorithm ed25519`` writes them, or as ``faultmas keys generate``
does.

Wire form: the envelope's JSON with two more fields at its end, ``"seq"`` then ``"sig"``::

    {"v":1,...,"content":"hello","seq":1764090000123456,"sig":"<base64 of 64 bytes>"}

``sig`` signs every byte before ``,"sig":`` (so every field, ``from`` and ``mas`` included). ``seq`` is the
sender's clock in microseconds, strictly increasing per sender: a receiver refuses a ``seq`` it has seen
from that sender (a replay) and one further than ``max_skew`` from its own clock (a replay from before
its own start, or a sender with a wrong clock). Control messages (``stop``) are signed the same way,
``by`` being the signer.
"""
from __future__ import annotations

import base64
import json
import os
import threading
import time
from pathlib import Path
from typing import Any, Iterable, Mapping

from agents.transport.envelope import BadMessage

#: Why a message is refused in the secure profile (counted and logged like every drop).
IDENTITY_DROP_REASONS = ("unsigned", "unknown_sender", "bad_signature", "replayed", "stale")

#: Seconds a ``seq`` may differ from the receiver's clock (hosts' clocks: NTP keeps them far closer).
DEFAULT_MAX_SKEW = 30.0

#: Sequence numbers remembered per (sender, receiver); older ones are refused outright (see ReplayGuard).
REPLAY_MEMORY = 4096

ENVIRONMENT = "$environment"
"""The identity of the environment: the process that serves the robots (the simulator's server, a robot driver).
It signs the robots' percepts, action results and clock, which steer the agents' beliefs; the agent that drives a
robot (the robot's namesake) signs the robot's actions with its own key. The project lists its public key as an
argument of its ``environment`` line (``environment: sim("key=keys/environment.pub")``), its private key stays
with the process that serves the robots. Why not the agents' keys: percepts come from the robots' process, not
from an agent, and a robot's own agent must not be able to forge what its robot perceives. ``$`` is no character
of an agent's name, so no envelope and no ``stop`` can claim to be the environment as a member."""

_SIG = b',"sig":"'
_SEQ = b',"seq":'
_SIG_LENGTH = 88  # base64 of 64 bytes



def claimed_agent(document: bytes) -> Any:
    """The agent a signed JSON document says it is from (its ``agent`` field; None when the document is not a
    JSON object): the ``sender_of`` that ``Identity.open`` checks the signature against. Bad JSON is
    ``BadMessage("not_json")``."""
    try:
        data = json.loads(document)
    except (ValueError, RecursionError) as exc:
        raise BadMessage("not_json", str(exc)[:80]) from None
    return data.get("agent") if isinstance(data, dict) else None

class IdentityError(ValueError):
    """A key file that cannot be used: names the file and why."""


def _crypto():
    from cryptography.exceptions import InvalidSignature
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric import ed25519
    return ed25519, serialization, InvalidSignature


def load_public_key(path: str | Path) -> Any:
    """The Ed25519 public key in PEM file ``path`` (``IdentityError`` naming the file otherwise)."""
    ed25519, serialization, _ = _crypto()
    data = _read_key_file(path)
    try:
        key = serialization.load_pem_public_key(data)
    except ValueError as exc:
        raise IdentityError(f"{path}: not a PEM public key ({str(exc)[:80]})") from None
    if not isinstance(key, ed25519.Ed25519PublicKey):
        raise IdentityError(f"{path}: expected an Ed25519 public key, got {type(key).__name__}")
    return key


def load_private_key(path: str | Path) -> Any:
    """The Ed25519 private key in PEM file ``path`` (unencrypted PKCS#8, as openssl writes it)."""
    ed25519, serialization, _ = _crypto()
    data = _read_key_file(path)
    try:
        key = serialization.load_pem_private_key(data, password=None)
    except (ValueError, TypeError) as exc:
        raise IdentityError(f"{path}: not an unencrypted PEM private key ({str(exc)[:80]})") from None
    if not isinstance(key, ed25519.Ed25519PrivateKey):
        raise IdentityError(f"{path}: expected an Ed25519 private key, got {type(key).__name__}")
    return key


def _read_key_file(path: str | Path) -> bytes:
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise IdentityError(f"{path}: cannot read the key: {exc.strerror or exc}") from None
    if len(data) > 16 * 1024:
        raise IdentityError(f"{path}: {len(data)} bytes is too large for a key file")
    return data


def generate_keys(directory: str | Path, names: Iterable[str]) -> list[Path]:
    """Write ``NAME.key`` (private, mode 0600) and ``NAME.pub`` in ``directory`` for each name; refuse to
    overwrite a private key (an agent's identity is not replaced by accident). Returns the files written."""
    ed25519, serialization, _ = _crypto()
    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name in names:
        private_path, public_path = folder / f"{name}.key", folder / f"{name}.pub"
        if private_path.exists():
            raise IdentityError(f"{private_path}: exists already; remove it to replace {name}'s identity")
        key = ed25519.Ed25519PrivateKey.generate()
        pem = key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                serialization.NoEncryption())
        descriptor = os.open(private_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
        with os.fdopen(descriptor, "wb") as out:
            out.write(pem)
        public_path.write_bytes(key.public_key().public_bytes(serialization.Encoding.PEM,
                                                              serialization.PublicFormat.SubjectPublicKeyInfo))
        written += [private_path, public_path]
    return written


class ReplayGuard:
    """Refuses a sequence number seen before from one sender to one receiver, and any too far from now.

    Memory is bounded: at most ``REPLAY_MEMORY`` numbers per pair; when full, the older half is forgotten
    and everything at or below it is refused from then on (messages of one sender to one receiver arrive
    nearly in order: a batch may overtake a question by a few messages, never by thousands)."""

    def __init__(self, max_skew: float = DEFAULT_MAX_SKEW) -> None:
        self.max_skew_us = int(max_skew * 1_000_000)
        self._floor: dict[tuple[str, str], int] = {}
        self._seen: dict[tuple[str, str], set[int]] = {}
        self._lock = threading.Lock()

    def check(self, sender: str, receiver: str, seq: int) -> str | None:
        """None if ``seq`` is fresh (and remember it), else the drop reason."""
        now = time.time_ns() // 1000
        if abs(seq - now) > self.max_skew_us:
            return "stale"
        pair = (sender, receiver)
        with self._lock:
            seen = self._seen.get(pair)
            if seen is None:
                seen = self._seen[pair] = set()
            if seq <= self._floor.get(pair, 0) or seq in seen:
                return "replayed"
            seen.add(seq)
            if len(seen) > REPLAY_MEMORY:
                ordered = sorted(seen)
                half = len(ordered) // 2
                self._floor[pair] = ordered[half - 1]
                self._seen[pair] = set(ordered[half:])
        return None


class Identity:
    """The keys one process knows: every member's public key, and the private keys of its own agents.

    ``seal`` signs what the process's agents send; ``open`` checks what they receive. One per transport.
    """

    def __init__(self, public_keys: Mapping[str, Any], private_keys: Mapping[str, Any] | None = None,
                 max_skew: float = DEFAULT_MAX_SKEW) -> None:
        self.public_keys = dict(public_keys)
        self.private_keys = dict(private_keys or {})
        self.replays = ReplayGuard(max_skew)
        self._last_seq: dict[str, int] = {}
        self._seq_lock = threading.Lock()
        self._invalid_signature = _crypto()[2]
        for name, key in self.private_keys.items():  # a private key must match the project's public one
            listed = self.public_keys.get(name)
            if listed is None or _raw_public(listed) != _raw_public(key.public_key()):
                raise IdentityError(f"the private key given for {name} does not match the public key the "
                                    "project lists for it" if listed is not None else
                                    f"{name} has a private key but the project lists no public key for it")

    @classmethod
    def from_files(cls, public_files: Mapping[str, str | Path], private_files: Mapping[str, str | Path] = (),
                   max_skew: float = DEFAULT_MAX_SKEW) -> "Identity":
        """Load the keys: ``public_files`` {member: PEM file}, ``private_files`` {own agent: PEM file}."""
        public = {name: load_public_key(path) for name, path in public_files.items()}
        private = {name: load_private_key(path) for name, path in dict(private_files).items()}
        return cls(public, private, max_skew)

    @property
    def members(self) -> frozenset[str]:
        """The agents of the project (not the environment: it signs robots' messages, it is no member)."""
        return frozenset(name for name in self.public_keys if name != ENVIRONMENT)

    def can_sign(self, name: str) -> bool:
        return name in self.private_keys

    def _next_seq(self, sender: str) -> int:
        now = time.time_ns() // 1000
        with self._seq_lock:
            seq = max(now, self._last_seq.get(sender, 0) + 1)
            self._last_seq[sender] = seq
        return seq

    # -- envelopes ----------------------------------------------------------------------------------
    def seal(self, sender: str, payload: bytes) -> bytes:
        """``payload`` (one encoded envelope or control object: JSON ending in ``}``) signed by ``sender``."""
        key = self.private_keys.get(sender)
        if key is None:
            raise IdentityError(f"no private key for {sender} in this process: it cannot send in the secure profile")
        signed = payload[:-1] + _SEQ + str(self._next_seq(sender)).encode()
        return signed + _SIG + base64.b64encode(key.sign(signed)) + b'"}'

    def open(self, payload: bytes, sender_of: Any) -> tuple[bytes, int]:
        """Check a sealed ``payload``: returns (the JSON to decode, its seq) or raises ``BadMessage``.
        ``sender_of(json_bytes)`` decodes the JSON and returns the claimed signer (it may raise
        ``BadMessage`` itself for bad JSON)."""
        at = payload.rfind(_SIG)
        if at < 0 or not payload.endswith(b'"}') or len(payload) - at - len(_SIG) - 2 != _SIG_LENGTH:
            document = payload
            sender = sender_of(document)
            raise BadMessage("unsigned", "the secure profile accepts only signed messages", sender)
        signed = payload[:at]
        document = signed + b"}"
        sender = sender_of(document)
        key = self.public_keys.get(sender) if isinstance(sender, str) else None
        if key is None:
            raise BadMessage("unknown_sender", f"{str(sender)[:40]!r} has no key in the project", None)
        try:
            signature = base64.b64decode(payload[at + len(_SIG):-2], validate=True)
            key.verify(signature, signed)
        except (ValueError, self._invalid_signature):
            raise BadMessage("bad_signature", f"not signed by {sender}'s key", sender) from None
        seq_at = signed.rfind(_SEQ)
        try:
            seq = int(signed[seq_at + len(_SEQ):]) if seq_at >= 0 else -1
        except ValueError:
            seq = -1
        if seq < 0:
            raise BadMessage("unsigned", "a signed message without its seq field", sender)
        return document, seq

    @staticmethod
    def as_sealed(document: bytes) -> bytes:
        """A document ``open`` returned, as it was given to ``seal`` (without its ``seq``)."""
        return document[:document.rfind(_SEQ)] + b"}"

    def check_fresh(self, sender: str, receiver: str, seq: int) -> None:
        """Raise ``BadMessage`` (``replayed``/``stale``) unless ``seq`` is new from ``sender`` to ``receiver``."""
        reason = self.replays.check(sender, receiver, seq)
        if reason is not None:
            raise BadMessage(reason, f"seq {seq}", sender)

    # -- control messages -------------------------------------------------------------------------
    def seal_control(self, message: Mapping[str, Any]) -> bytes:
        """A control message signed by its ``by`` (one of this process's agents)."""
        return self.seal(str(message.get("by")), json.dumps(message, separators=(",", ":")).encode())

    def open_control(self, payload: bytes) -> dict[str, Any]:
        """The control message in a sealed ``payload``, its ``by`` proved (``BadMessage`` otherwise)."""
        def signer(document: bytes) -> Any:
            try:
                message = json.loads(document)
            except (ValueError, RecursionError) as exc:
                raise BadMessage("not_json", str(exc)[:80]) from None
            if not isinstance(message, dict):
                raise BadMessage("not_json", "expected a JSON object")
            return message.get("by")

        document, seq = self.open(payload, signer)
        message = json.loads(document)
        self.check_fresh(str(message.get("by")), "control", seq)
        message.pop("seq", None)
        return message


def _raw_public(key: Any) -> bytes:
    _, serialization, _ = _crypto()
    return key.public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)


def environment_key_option(project: Any) -> str | None:
    """The ``key=`` argument of the project's ``environment`` line (the environment's public key), or None."""
    for text in getattr(project, "environment_args", None) or ():
        if text.startswith("key="):
            return text[len("key="):]
    return None


def project_key_files(project: Any) -> dict[str, Path]:
    """{agent: public key file} from the ``key=`` options of a ``MasProject`` (empty when none has one), and
    ``ENVIRONMENT``'s from its ``environment`` line's ``key=`` argument (a directory means
    ``<dir>/environment.pub``). Every agent then needs one: a project half in the secure profile is refused
    (``IdentityError``)."""
    base = Path(project.file).resolve().parent if project.file else Path.cwd()
    files: dict[str, Path] = {}
    missing = []
    environment = environment_key_option(project)
    if environment is not None:
        path = base / environment
        files[ENVIRONMENT] = path / "environment.pub" if path.is_dir() else path
    for decl in project.agents:
        option = decl.options.get("key")
        for name in decl.instance_names():
            if option is None:
                missing.append(name)
                continue
            path = base / str(option)
            files[name] = path / f"{name}.pub" if path.is_dir() else path
    if files and missing:
        raise IdentityError(f"{project.file}: agents {', '.join(missing)} have no key= option, but others (or the environment) do: "
                            "in the secure profile every agent of the project needs its public key")
    return files


def private_key_file(public_file: Path) -> Path:
    """Where an agent's private key is by default: beside its public key, ``.key`` for ``.pub``."""
    return public_file.with_suffix(".key")


def project_identity(project: Any, own_agents: Iterable[str] = (), private_file: str | Path | None = None,
                     max_skew: float = DEFAULT_MAX_SKEW) -> Identity | None:
    """The secure profile of ``project`` for a process running ``own_agents`` (None: the project lists no
    keys, the default profile). Each own agent's private key is ``private_file`` (one agent only) or the
    ``.key`` beside its public key. ``IdentityError`` names the file or agent that is missing."""
    public = project_key_files(project)
    own = list(own_agents)
    if not public:
        if private_file is not None:
            raise IdentityError(f"{project.file}: an identity was given but the project lists no key= "
                                "for its agents (the secure profile needs every member's public key)")
        return None
    if private_file is not None and len(own) != 1:
        raise IdentityError("one private key file was given for several agents")
    private = {}
    for name in own:
        if name == ENVIRONMENT and name not in public:
            raise IdentityError(f"{project.file}: the secure profile serves robots only with the environment's "
                                'key: add it to the environment line, e.g. environment: sim("key=keys/environment.pub")')
        if name not in public:
            raise IdentityError(f"{project.file}: {name} is not an agent of the project, so it has no key")
        private[name] = Path(private_file) if private_file is not None else private_key_file(public[name])
    return Identity.from_files(public, private, max_skew)


def project_identity_of_key(project: Any, private_file: str | Path,
                            max_skew: float = DEFAULT_MAX_SKEW) -> Identity:
    """The secure profile of ``project`` for a process that is no agent but holds ``private_file``, the private
    key of one of the identities the project lists (a member's, or the environment's): ``faultmas inspect
    --identity`` signs pause and step with it. ``IdentityError`` when the project lists no keys or not this one."""
    public = project_key_files(project)
    if not public:
        raise IdentityError(f"{project.file}: an identity was given but the project lists no key= "
                            "(not the secure profile)")
    raw = _raw_public(load_private_key(private_file).public_key())
    for name, path in public.items():
        if _raw_public(load_public_key(path)) == raw:
            return Identity.from_files(public, {name: private_file}, max_skew)
    raise IdentityError(f"{private_file}: not the private key of any identity {project.file} lists")
