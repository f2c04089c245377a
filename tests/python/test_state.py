"""The state block's reader: the sequence lock, following every tick, refusing what it cannot
read. The block is written as the daemon writes it (fake_daemon.Block)."""

from __future__ import annotations

import os
import struct
import tempfile
import threading
import time
import unittest

import hapticd
from fake_daemon import HEADER, Block


def open_block(block: Block) -> hapticd.State:
    return hapticd.State(os.dup(block.fd), expect=block.description(), name="test block")


class StateTest(unittest.TestCase):
    def setUp(self) -> None:
        self.block = Block(slots=8)
        self.addCleanup(self.block.close)
        self.state = open_block(self.block)
        self.addCleanup(self.state.close)

    def test_the_header_is_read(self) -> None:
        s = self.state
        self.assertEqual((s.slots, s.joints, s.axes, s.sample_period_ns), (8, 3, 3, 1_000_000))
        self.assertEqual(s.head, 0)

    def test_latest_is_the_newest_complete_sample(self) -> None:
        for _ in range(11):  # laps the ring once
            self.block.write()
        sample = self.state.latest()
        assert sample is not None
        self.assertEqual((sample.index, sample.tick), (10, 1010))
        self.assertEqual(sample.measured_cp, (14.0, 14.25, 14.5))
        self.assertEqual(sample.flags, hapticd.TickFlag.SATURATED)  # 10 & 7

    def test_a_torn_slot_is_not_returned(self) -> None:
        for _ in range(5):
            self.block.write()
        self.block.begin(5)  # sample 5 half-written...
        self.block.set_head(6)  # ...though head already counts it
        self.assertIsNone(self.state.read(5))
        sample = self.state.latest()
        assert sample is not None
        self.assertEqual(sample.index, 4)  # the newest complete one instead
        self.assertEqual(sample.x, (8.0, 8.25, 8.5))

    def test_an_overwritten_slot_is_not_returned_as_the_sample_asked_for(self) -> None:
        for _ in range(10):
            self.block.write()
        self.assertIsNone(self.state.read(1))  # slot 1 holds sample 9 now
        self.assertEqual(self.state.read(9).tick, 1009)  # type: ignore[union-attr]

    def test_follow_yields_every_sample_in_order_from_the_next_one(self) -> None:
        self.block.write()
        follower = self.state.follow()
        for _ in range(5):
            self.block.write()
        follower.until_ns = time.monotonic_ns()  # ends once caught up
        self.assertEqual([s.index for s in follower], [1, 2, 3, 4, 5])
        self.assertEqual((follower.read, follower.missed), (5, 0))

    def test_follow_counts_what_the_writer_overwrote_before_it_was_read_as_missed(self) -> None:
        follower = self.state.follow(until_ns=time.monotonic_ns())
        for _ in range(13):  # 5 more than the 8 slots hold
            self.block.write()
        self.assertEqual([s.index for s in follower], list(range(5, 13)))
        self.assertEqual((follower.read, follower.missed), (8, 5))

    def test_follow_counts_a_slot_overwritten_under_it_as_missed(self) -> None:
        for _ in range(5):
            self.block.write()
        self.block.set_seq(2, 2 * 10 + 1)  # sample 10 being written over sample 2
        follower = self.state.follow(start=0, until_ns=time.monotonic_ns())
        self.assertEqual([s.index for s in follower], [0, 1, 3, 4])
        self.assertEqual(follower.missed, 1)

    def test_follow_waits_for_a_slot_being_written(self) -> None:
        for _ in range(3):
            self.block.write()
        self.block.begin(3)
        self.block.set_head(4)
        follower = self.state.follow(start=2)
        self.assertEqual(next(follower).index, 2)
        threading.Timer(0.05, self.block.write, args=(3,)).start()
        self.assertEqual(next(follower).index, 3)  # not skipped: it completes
        self.assertEqual(follower.missed, 0)

    def test_follow_ends_at_the_first_sample_at_or_after_until_ns(self) -> None:
        for _ in range(6):
            self.block.write()
        follower = self.state.follow(start=0, until_ns=Block.values(4)[1])
        self.assertEqual([s.index for s in follower], [0, 1, 2, 3])

    def test_following_a_concurrent_writer_reads_no_torn_sample(self) -> None:
        total = 3000
        block = Block(slots=64)
        self.addCleanup(block.close)
        state = open_block(block)
        self.addCleanup(state.close)
        follower = state.follow(start=0, poll_s=0.0001)

        def writer() -> None:
            for n in range(total):
                block.write()
                if n % 20 == 0:
                    time.sleep(0.0005)
            follower.until_ns = time.monotonic_ns() + 50_000_000

        thread = threading.Thread(target=writer)
        thread.start()
        indices = []
        for sample in follower:
            self.assertEqual(sample.tick, 1000 + sample.index)
            self.assertEqual(sample.f, tuple(6 + sample.index + d for d in (0, 0.25, 0.5)))
            indices.append(sample.index)
        thread.join()
        self.assertEqual(indices, sorted(set(indices)))
        self.assertEqual(follower.read + follower.missed, total)
        self.assertEqual(follower.read, len(indices))

    def test_a_closed_block_says_so(self) -> None:
        self.state.close()
        with self.assertRaisesRegex(hapticd.StateError, "test block: closed"):
            self.state.latest()


class RefusedBlockTest(unittest.TestCase):
    def block_file(self, size: int = 128 + 4 * 192, **fields: object) -> str:
        header = {"magic": b"HAPTSTAT", "layout": 1, "header_bytes": 128, "slot_bytes": 192,
                  "slots": 4, "period": 1_000_000, "joints": 3, "axes": 3, "head": 0, **fields}
        data = bytearray(size)
        HEADER.pack_into(data, 0, *header.values())
        f = tempfile.NamedTemporaryFile(prefix="hapticd-state-", delete=False)
        self.addCleanup(os.unlink, f.name)
        with f:
            f.write(data)
        return f.name

    def assert_refused(self, path: str, message: str) -> None:
        with self.assertRaises(hapticd.StateError) as caught:
            hapticd.State.open(path)
        self.assertIn(f"{path}: {message}", str(caught.exception))

    def test_a_good_file_opens(self) -> None:
        with hapticd.State.open(self.block_file()) as state:
            self.assertEqual(state.slots, 4)
            self.assertIsNone(state.latest())

    def test_a_wrong_magic_is_refused(self) -> None:
        self.assert_refused(self.block_file(magic=b"NOTSTATE"),
                            "magic b'NOTSTATE', expected b'HAPTSTAT': not a hapticd state block")

    def test_another_layout_is_refused(self) -> None:
        self.assert_refused(self.block_file(layout=2),
                            "layout 2, this package reads layout 1")

    def test_sizes_it_cannot_read_are_refused_naming_the_field(self) -> None:
        for fields, message in (({"slots": 3}, "slots 3 is not a power of two"),
                                ({"slot_bytes": 96}, "slot_bytes 96, expected 192"),
                                ({"header_bytes": 64}, "header_bytes 64, expected 128"),
                                ({"axes": 0}, "axes 0, expected 1 to 3"),
                                ({"slots": 8}, "896 bytes, its header describes 1664")):
            with self.subTest(fields=fields):
                self.assert_refused(self.block_file(**fields), message)

    def test_a_file_shorter_than_the_header_is_refused(self) -> None:
        self.assert_refused(self.block_file(size=64), "64 bytes, smaller than the 128-byte header")

    def test_a_missing_file_names_the_path(self) -> None:
        with self.assertRaisesRegex(hapticd.StateError, "/nonexistent/state: cannot open it"):
            hapticd.State.open("/nonexistent/state")


if __name__ == "__main__":
    unittest.main()
