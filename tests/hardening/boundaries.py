"""Every input boundary of faultmas as one function ``bytes -> None`` and the errors it may raise: the
project's own located errors. Used by the fuzz tests (``test_fuzz_boundaries``) and the long campaign
(``make campaign``). Anything else raised (or a crash, or a hang) is a defect."""
from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Callable

from agents.transport.envelope import BadMessage, decode
from agents.zenoh_arch import ContentCache
from agentspeak.errors import FaultmasError, SourceError
from agentspeak.mas2j import parse_mas2j
from agentspeak.parser import parse_program_all_errors
from diagnosis.cli import read_observations
from diagnosis.formula import FormulaSyntaxError, parse_formula, to_cnf
from diagnosis.loader import load_model
from detection.config import load_observers
from detection.taps.bag import BagError, replay
from perception.cli import InputError, load_frame

_SCRATCH = Path(tempfile.mkdtemp(prefix="faultmas-fuzz-"))


def _text(data: bytes) -> str:
    return data.decode("utf-8", "replace")


def asl_program(data: bytes) -> None:
    path = _SCRATCH / "fuzz.asl"
    path.write_bytes(data)
    from agentspeak.source_text import read_source
    program, _errors = parse_program_all_errors(read_source(path), str(path))
    for plan in program.plans:  # what an agent does with a parsed plan first: print and copy it
        str(plan)


def message_content(data: bytes) -> None:
    term = ContentCache().parse(_text(data))
    str(term), hash(term)  # what the agent layer does with a received term: logs and belief base


def envelope(data: bytes) -> None:
    decode(data)


def mas2j_project(data: bytes) -> None:
    parse_mas2j(_text(data), "fuzz.mas2j")


def formula(data: bytes) -> None:
    counter = iter(range(10 ** 9))
    to_cnf(parse_formula(_text(data)), lambda lit: 1 + hash(lit) % 1000, lambda: 2000 + next(counter))


def yaml_model(data: bytes) -> None:
    path = _SCRATCH / "fuzz.yaml"
    path.write_bytes(data)
    load_model(path)


def bench_model(data: bytes) -> None:
    path = _SCRATCH / "fuzz.bench"
    path.write_bytes(data)
    load_model(path)


def observations(data: bytes) -> None:
    path = _SCRATCH / "obs.json"
    path.write_bytes(data)
    read_observations(str(path))


def perception_image(data: bytes) -> None:
    """A camera frame given to perception as ``faultmas perceive`` reads it: a PNG beside a depth array."""
    from perception.camera import CameraModel
    from perception.detect import detect_all

    rgb_path = _SCRATCH / "frame.png"
    rgb_path.write_bytes(data)
    rgb, depth = load_frame(str(rgb_path), str(_seed_depth()))
    detect_all(rgb, depth, CameraModel.from_fov(57.0, 43.0, rgb.shape[1], rgb.shape[0]))


def perception_depth(data: bytes) -> None:
    """A depth array (``.npy``) given to perception beside a valid colour frame."""
    from perception.camera import CameraModel
    from perception.detect import detect_all

    depth_path = _SCRATCH / "depth.npy"
    depth_path.write_bytes(data)
    rgb, depth = load_frame(str(_seed_image_file()), str(depth_path))
    detect_all(rgb, depth, CameraModel.from_fov(57.0, 43.0, rgb.shape[1], rgb.shape[0]))


def observer_config(data: bytes) -> None:
    path = _SCRATCH / "observers.yaml"
    path.write_bytes(data)
    load_observers(path).build()


def bag(data: bytes) -> None:
    """A recorded bag whose data file is ``data`` (its metadata from a valid bag): replayed as
    ``faultmas observe --bag`` does, every message's fields decoded."""
    import shutil

    folder = _SCRATCH / "bag"
    shutil.rmtree(folder, ignore_errors=True)
    seed = _seed_bag()
    shutil.copytree(seed, folder)
    (folder / _bag_data_file(seed).name).write_bytes(data)
    for message in replay(folder, ["/scan"]):
        if message.raw is not None:
            try:
                message.decoded()
            except BagError:
                raise
            except Exception:  # an undecodable message: the tap counts it and goes on (detection/taps)
                pass


_SEEDS: dict[str, object] = {}


def _seed_frame():
    """A 64x48 frame with a red and a green upright bar on grey, 1.5 m away: what the detector looks for."""
    import numpy as np

    if "frame" not in _SEEDS:
        rgb = np.full((48, 64, 3), 90, np.uint8)
        rgb[10:40, 20:26] = (200, 30, 30)
        rgb[10:40, 34:40] = (30, 180, 40)
        _SEEDS["frame"] = (rgb, np.full((48, 64), 1.5, np.float32))
    return _SEEDS["frame"]


def _seed_image_file() -> Path:
    import cv2

    path = _SCRATCH / "seed.png"
    if not path.exists():
        cv2.imwrite(str(path), cv2.cvtColor(_seed_frame()[0], cv2.COLOR_RGB2BGR))
    return path


def _seed_depth() -> Path:
    import numpy as np

    path = _SCRATCH / "seed_depth.npy"
    if not path.exists():
        np.save(path, _seed_frame()[1])
    return path


def _seed_bag() -> Path:
    """A small MCAP bag as a tap records it: start marker, /scan Float64 at 10 Hz, one bad message."""
    from detection.message import Message
    from detection.taps import codec
    from detection.taps.bag import BagRecorder

    folder = _SCRATCH / "seed_bag"
    if not folder.exists():
        store = codec.typestore()
        floats = store.types["std_msgs/msg/Float64"]
        recorder = BagRecorder(folder)
        recorder.start(10 ** 9)
        for i in range(5):
            raw = bytes(store.serialize_cdr(floats(data=float(i)), "std_msgs/msg/Float64"))
            recorder.write(Message("/scan", 10 ** 9 + i * 10 ** 8, raw=raw), "std_msgs/msg/Float64")
        recorder.write(Message("/scan", 2 * 10 ** 9, raw=b"\x00\x01"), "std_msgs/msg/Float64")
        recorder.stop(3 * 10 ** 9)
        recorder.close()
    return folder


def _bag_data_file(folder: Path) -> Path:
    return next(p for p in folder.iterdir() if p.suffix in (".mcap", ".db3"))


def _seed_bytes(make: Callable[[], Path], data_file: bool = False) -> list[bytes]:
    path = make()
    return [(_bag_data_file(path) if data_file else path).read_bytes()]


OBSERVER_SEED = b"""main_loop_rate: 10
start_up_time: 1.0
setup:
  - type: hz
    topics:
      - name: /scan
        filter: {type: median, window_size: 10}
        states:
          - state: nominal
            number: 1
            frequency: {type: gauss, mean: 10.0, std_deviation: 1.0}
  - type: timeout
    topics:
      - name: /odom
        timeout: 0.5
  - type: score
    topics:
      - name: /battery
        msg_type: std_msgs/msg/Float64
        field: data
        states: [{state: ok, score: {type: greater_than, greater_than: 11.0}}]
"""

#: name -> (the boundary, the errors it may raise, seeds: valid inputs to mutate)
BOUNDARIES: dict[str, tuple[Callable[[bytes], None], tuple[type[BaseException], ...], list[bytes]]] = {
    "asl": (asl_program, (FaultmasError,), [
        b"!start.\n+!start : true <- .print(\"hi\", 1 + 2 * X); ?b(X); -+c([1,2|T]).\n",
        b"b(1). r(X) :- b(X) & not c(X).\n@l[atomic] +!g(N) : N > 0 <- .send(bob, tell, m(N)); !g(N-1).\n",
        b"+!w <- while (X < 3) { X = X + 1 }; if (a) { .print(a) } else { .fail }.\n"]),
    "content": (message_content, (FaultmasError,), [
        b"pos(3,-4.5,\"x\",a)", b"[a,b|[]]", b"~p(1)[source(self),x(\"s\")]", b"{+!g <- .print(1)}", b"X + 1"]),
    "envelope": (envelope, (BadMessage,), [
        b'{"v":1,"id":"a.1","mas":"m","from":"alice","to":["bob"],"perf":"tell","content":"p(1)"}',
        b'{"v":1,"id":"a.2","mas":"m","from":"bob","to":["alice"],"perf":"tell","content":"x","re":"a.1"}']),
    "mas2j": (mas2j_project, (FaultmasError,), [
        b"MAS rescue {\n  infrastructure: Centralised\n  agents:\n    alice; bob agentArchClass Foo #3;\n"
        b"    carol [beliefs=\"b(1)\", goals=\"g\"];\n  aslSourcePath: \"src\";\n}\n"]),
    "formula": (formula, (FormulaSyntaxError,), [
        b"!AB(left_motor) -> (left_torque <-> commanded_forward)", b"(a & b) | !c -> hz(scan)"]),
    "yaml_model": (yaml_model, (SourceError,), [
        b"system: s\ncomponents: [m]\nobservations: [o]\nvariables: [v]\nbehaviour:\n  - \"!AB(m) -> (v <-> o)\"\n"]),
    "bench_model": (bench_model, (SourceError,), [
        b"INPUT(a)\nINPUT(b)\nOUTPUT(c)\nc = NAND(a, b)\n"]),
    "observations": (observations, (SourceError,), [b'{"o": 1, "p": false}']),
    "image": (perception_image, (InputError,), _seed_bytes(_seed_image_file)),
    "depth": (perception_depth, (InputError,), _seed_bytes(_seed_depth)),
    "observer_config": (observer_config, (SourceError,), [OBSERVER_SEED]),
    "bag": (bag, (BagError,), _seed_bytes(_seed_bag, data_file=True)),
}
