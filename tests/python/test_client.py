"""The control socket's client against a fake daemon that follows protocol version 1."""

from __future__ import annotations

import math
import os
import socket
import tempfile
import time
import unittest
from typing import Any

import hapticd
from fake_daemon import Block, FakeDaemon, refuse


class Scene:
    """A daemon's scene requests as the real one answers them (service/run/run_reload.cpp)."""

    def __init__(self) -> None:
        self.walls: list[dict[str, Any]] = [{"point": [0.02, 0, 0.11], "normal": [1, 0, 0],
                                             "stiffness": 500, "damping": 0.05}]
        self.tick = 100
        self.streaming = 0  # the stream's every, 0: none

    def __call__(self, request: dict[str, Any]) -> dict[str, Any] | None:
        cmd = request["cmd"]
        if cmd == "status":
            # While streaming, two samples reach the client before the answer.
            samples = [{"v": 1, "stream": {"tick": self.tick + k * self.streaming, "missed": 0}}
                       for k in range(2)] if self.streaming else []
            return {"status": {"schema_version": 8, "state": "running", "tick": self.tick,
                               "walls": [{"stiffness": w["stiffness"]} for w in self.walls]},
                    "_lines_before": samples}
        if cmd == "stop":
            return {"stopping": True}
        if cmd == "reload":
            return {"reload": {"accepted": True, "applied_at_tick": self.tick, "gate": {}}}
        if cmd == "silence":
            return None
        if cmd == "stream":
            self.streaming = request["every"]
            return {"stream": {"every": self.streaming, "rate_hz": 1000 / max(1, self.streaming),
                               "first_sample": self.tick}}
        if cmd != "scene":
            return refuse(f"unknown command '{cmd}'", 2)
        op, index = request["op"], request.get("index", len(self.walls))
        if op != "add" and not 0 <= index < len(self.walls):
            return refuse(f"scene {op} refused: index {index} names no wall", 2)
        self.tick += 1
        if op == "move":
            return {"scene": {"op": "move", "index": index, "applied_at_tick": self.tick,
                              "applied_at_ns": time.monotonic_ns()}}
        if op == "add":
            if request["wall"]["stiffness"] > 1e5:
                return refuse("scene add refused: the gate refuses it: walls[1]: K 1e+07 N/m "
                              "exceeds the passive limit 2.1e+04 N/m", 3)
            self.walls.append(request["wall"])
        elif op == "change":
            self.walls[index].update(request["wall"])
        elif op == "remove":
            del self.walls[index]
        return {"scene": {"accepted": True, "applied_at_tick": self.tick, "gate": {"pass": True},
                          "op": op, "index": index, "walls": len(self.walls)}}


class ClientTest(unittest.TestCase):
    def setUp(self) -> None:
        self.scene = Scene()
        self.daemon = FakeDaemon(self.scene)
        self.addCleanup(self.daemon.close)
        self.client = hapticd.Client(self.daemon.path, timeout=5)
        self.addCleanup(self.client.close)

    def test_status_is_the_answers_status_member_and_requests_carry_v_and_id(self) -> None:
        status = self.client.status()
        self.assertEqual(status["state"], "running")
        self.assertEqual(status["tick"], 100)
        self.client.stop()
        first, second = self.daemon.requests
        self.assertEqual(first["v"], 1)
        self.assertEqual((first["cmd"], second["cmd"]), ("status", "stop"))
        self.assertNotEqual(first["id"], second["id"])  # each answer matched to its request

    def test_reload_sends_the_text_and_source(self) -> None:
        answer = self.client.reload("walls: []\n", source="box.yaml")
        self.assertEqual(answer["applied_at_tick"], 100)
        self.assertEqual(self.daemon.requests[0]["config"], "walls: []\n")
        self.assertEqual(self.daemon.requests[0]["source"], "box.yaml")

    def test_add_change_remove_send_a_walls_keys_and_return_what_was_answered(self) -> None:
        index = self.client.add_wall((0, 0, 0.16), [0, 0, 1], 400, 0.1, no_pull=True)
        self.assertEqual(index, 1)
        self.assertEqual(self.daemon.requests[-1]["wall"],
                         {"point": [0.0, 0.0, 0.16], "normal": [0.0, 0.0, 1.0], "stiffness": 400,
                          "damping": 0.1, "no_pull": True})
        changed = self.client.change_wall(1, stiffness=300)
        self.assertEqual(self.daemon.requests[-1]["wall"], {"stiffness": 300})  # only that key
        self.assertEqual(changed["index"], 1)
        removed = self.client.remove_wall(0)
        self.assertEqual((removed["op"], removed["walls"]), ("remove", 1))
        self.assertEqual(self.scene.walls[0]["stiffness"], 300)

    def test_add_attractor_sends_an_attractors_keys_without_a_normal(self) -> None:
        index = self.client.add_attractor([0.01, 0, 0.11], 100, 0.05, max_force=2.0, keep=True)
        self.assertEqual(index, 1)
        request = self.daemon.requests[-1]
        self.assertEqual(request["wall"],
                         {"kind": "attractor", "point": [0.01, 0.0, 0.11], "stiffness": 100,
                          "damping": 0.05, "max_force": 2.0})
        self.assertIs(request["keep"], True)
        self.client.add_attractor([0, 0, 0.1], 50)
        self.assertEqual(self.daemon.requests[-1]["wall"],
                         {"kind": "attractor", "point": [0.0, 0.0, 0.1], "stiffness": 50})
        self.assertNotIn("keep", self.daemon.requests[-1])  # as the daemon's default says
        with self.assertRaises(ValueError):
            self.client.add_attractor([0, float("nan"), 0.1], 50)

    def test_stream_samples_that_come_before_an_answer_are_kept_for_samples(self) -> None:
        started = self.client.stream(10)
        self.assertEqual((started["every"], started["rate_hz"]), (10, 100))
        self.assertEqual(self.daemon.requests[-1]["every"], 10)
        status = self.client.status()  # two samples arrive first: not taken for the answer
        self.assertEqual(status["tick"], 100)
        got = list(self.client.samples(timeout=0.2))
        self.assertEqual([s["tick"] for s in got], [100, 110])
        self.assertEqual(self.client.status()["state"], "running")  # still in step

    def test_move_returns_the_tick_and_time_it_was_applied_at(self) -> None:
        sent = time.monotonic_ns()
        answer = self.client.move_wall(0, [0.025, 0, 0.11])
        self.assertEqual(self.daemon.requests[-1],
                         {"v": 1, "id": 1, "cmd": "scene", "op": "move", "index": 0,
                          "point": [0.025, 0.0, 0.11]})
        self.assertEqual(answer["applied_at_tick"], 101)
        self.assertGreaterEqual(answer["applied_at_ns"], sent)

    def test_a_gate_refusal_raises_refused_with_code_3_and_the_gates_numbers(self) -> None:
        with self.assertRaises(hapticd.Refused) as caught:
            self.client.add_wall([0, 0, 0.16], [0, 0, 1], 1e7)
        self.assertEqual(caught.exception.code, 3)
        self.assertIn("exceeds the passive limit 2.1e+04 N/m", caught.exception.error)
        self.assertIn(self.daemon.path, str(caught.exception))
        self.assertIn("scene add", str(caught.exception))
        self.assertEqual(len(self.scene.walls), 1)
        self.assertEqual(self.client.status()["state"], "running")  # the connection goes on

    def test_a_malformed_request_raises_refused_with_code_2(self) -> None:
        with self.assertRaises(hapticd.Refused) as caught:
            self.client.remove_wall(7)
        self.assertEqual(caught.exception.code, 2)
        self.assertIn("index 7 names no wall", caught.exception.error)

    def test_bad_vectors_are_refused_before_sending_naming_the_argument(self) -> None:
        for point, why in (([math.nan, 0, 0], "not finite"), ([0, 0, 0, 0], "got 4"),
                           ("abc", "expected 1 to 3 numbers")):
            with self.subTest(point=point), self.assertRaisesRegex(ValueError, f"point: .*{why}"):
                self.client.move_wall(0, point)
        with self.assertRaisesRegex(ValueError, "not valid JSON"):
            self.client.change_wall(0, stiffness=math.inf)
        self.assertEqual(self.daemon.requests, [])

    def test_no_daemon_at_the_path_names_the_path(self) -> None:
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "missing.sock")
            with self.assertRaisesRegex(hapticd.ClientError, f"{path}: cannot connect"):
                hapticd.Client(path)

    def test_no_answer_in_time_is_a_client_error_and_ends_the_connection(self) -> None:
        client = hapticd.Client(self.daemon.path, timeout=0.2)
        self.addCleanup(client.close)
        with self.assertRaisesRegex(hapticd.ClientError,
                                    f"{self.daemon.path}: no answer to silence within 0.2 s"):
            client.request({"cmd": "silence"})
        with self.assertRaisesRegex(hapticd.ClientError, "failed earlier .*open a new Client"):
            client.status()  # its answer would be taken for the silent request's

    def test_the_daemon_closing_the_connection_is_a_client_error(self) -> None:
        self.client.status()
        self.daemon.drop_connections(socket.SHUT_WR)  # reads the request, never answers
        with self.assertRaisesRegex(hapticd.ClientError, "status: the daemon closed the "
                                    "connection without answering"):
            self.client.status()

    def test_an_answer_to_another_request_is_a_client_error(self) -> None:
        self.daemon.handler = lambda request: {"id": 99}
        with self.assertRaisesRegex(hapticd.ClientError, "answer's id 99, sent 1"):
            self.client.stop()

    def test_state_without_a_descriptor_is_a_client_error(self) -> None:
        self.daemon.handler = lambda request: {"state": Block().description()}
        with self.assertRaisesRegex(hapticd.ClientError, "state: the answer came with 0 file "
                                    "descriptors, expected one"):
            self.client.state()


class StateOverSocketTest(unittest.TestCase):
    def setUp(self) -> None:
        self.block = Block(slots=8, joints=3, axes=2)
        self.addCleanup(self.block.close)
        self.daemon = FakeDaemon(lambda request: {"state": self.block.description()}, self.block)
        self.addCleanup(self.daemon.close)
        self.client = hapticd.Client(self.daemon.path, timeout=5)
        self.addCleanup(self.client.close)

    def test_the_passed_block_is_mapped_and_read_with_crtk_names(self) -> None:
        with self.client.state() as state:
            self.assertIsNone(state.latest())
            for _ in range(3):
                self.block.write()
            sample = state.latest()
            assert sample is not None
            self.assertEqual((sample.index, sample.tick, sample.time_ns), (2, 1002, 7_000_000))
            self.assertEqual(sample.measured_js.position, (3.0, 3.25, 3.5))
            self.assertEqual(sample.measured_js.velocity, (4.0, 4.25, 4.5))
            self.assertEqual(sample.measured_js.effort, (5.0, 5.25, 5.5))
            self.assertEqual(sample.measured_cp, (6.0, 6.25))  # two task axes
            self.assertEqual(sample.measured_cv, (7.0, 7.25))
            self.assertEqual(sample.setpoint_cf, (8.0, 8.25))
            self.assertEqual(sample.observer_energy_j, 0.25)
            self.assertEqual(sample.flags, hapticd.TickFlag.SATURATED)
            self.assertTrue(sample.in_contact(1))
            self.assertFalse(sample.in_contact(0))
            self.assertEqual(sample.fault_cause, 0)
        self.assertEqual(self.daemon.requests[0]["cmd"], "state")

    def test_a_block_that_disagrees_with_the_answer_is_refused(self) -> None:
        self.daemon.handler = lambda request: {"state": {**self.block.description(), "slots": 16}}
        with self.assertRaisesRegex(hapticd.StateError, "state block: header's slots 8 differs "
                                    "from the daemon's answer's 16"):
            self.client.state()


if __name__ == "__main__":
    unittest.main()
