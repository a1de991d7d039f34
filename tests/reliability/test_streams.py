"""Event-stream clients that stop reading, or go away, cost the controller nothing: bounded, marked, removed."""
from __future__ import annotations

import signal

from controlproc import ControllerProcess
from flood import Flood
from probes import idle_subscribers, read_events, tasks

SERVO = "RFLEX.servo"


def modules_up(client) -> None:
    from runkit import navigation_ready, ndd_settings

    navigation_ready(client)
    ndd_settings(client)


def test_stream_clients_that_stop_reading_then_disconnect_are_gone_at_once():
    with ControllerProcess() as ctl:
        ctl.wait_ready()
        client = ctl.client()
        modules_up(client)  # LaserRF scans, Aspect maps: poster events on every stream
        base = client.info()["events"]["streams"]
        socks = idle_subscribers(ctl.url, 50)
        assert ctl.wait_for(lambda: client.info()["events"]["streams"] == base + 50)
        # they stop reading: their streams fall behind (their socket buffers are full)
        assert ctl.wait_for(lambda: client.info()["events"]["behind"] >= 50, timeout=120), client.info()["events"]
        for s in socks:
            s.close()
        assert ctl.wait_for(lambda: client.info()["events"]["streams"] == base, timeout=30), client.info()["events"]
        end = ctl.stop(signal.SIGINT)
    assert end.status == 0 and "Traceback" not in end.err, end.err[-3000:]
    assert end.took < 10, end.took


def test_subscribers_that_never_read_get_a_bounded_queue_then_a_marked_gap_and_slow_nothing_else():
    with ControllerProcess() as ctl:
        ctl.wait_ready()
        client = ctl.client()
        modules_up(client)
        socks = idle_subscribers(ctl.url, 200)
        assert ctl.wait_for(lambda: client.info()["events"]["behind"] >= 200, timeout=120), client.info()["events"]
        before = tasks(client)[SERVO]
        first = client.requests(limit=1)[0]["id"] + 1
        flood = Flood(ctl.url, 600, 4, wait_every=2, first_id=first)
        seen = flood.run()
        after = tasks(client)[SERVO]
        stats = client.info()["events"]
        # each stalled stream holds at most the queue's bound, and what it missed is counted
        assert stats["streams"] >= 200 and 0 < stats["most_behind"] <= stats["queue_bound"], stats
        assert stats["dropped"] > 0, stats
        # the engine waited for none of them: it ran RFLEX's periods and answered every request while all 200
        # streams were blocked (bench/reliability_bench.py measures the periods missed, on a quiet machine)
        assert after["periods"] > before["periods"]
        assert len(seen.answers) == 300 and all(seen.answers.values()) and len(seen.polls) == 300
        assert client.info()["events"]["behind"] >= 200
        # one of them reads again: a gap marked with what it lost, and still every final report of the flood
        accepted = seen.sent_202 | set(seen.answers)
        resumed = read_events(socks[0], lambda evs: accepted <= {e.get("request") for e in evs if e.get("final")},
                              timeout=120)
        gaps = [e for e in resumed if e["event"] == "gap"]
        assert gaps and all(g["dropped"] > 0 and "fell behind" in g["message"] for g in gaps), gaps[:3]
        end = ctl.stop(signal.SIGINT)
        for s in socks:
            s.close()
    assert end.status == 0 and "Traceback" not in end.err, end.err[-3000:]
