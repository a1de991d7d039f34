"""A flood of requests from concurrent clients, and what came back on every channel a final report travels.

``Flood(url).run()`` sends ``requests`` requests to DALA's attributes and functions from ``clients``
threads, each on its own keep-alive connection: one in two waits for its answer (``POST ?wait=60``, the
answer carries the final report), the other is sent and forgotten (``202``) and long-polled by a pool of
pollers (``GET /requests/N?wait=60``).  A listener reads ``/events`` all along.  ``on_accepted=(n, f)``
calls ``f()`` once ``n`` requests have been accepted (a signal in the middle of the flood).
:meth:`Flood.missing` compares the channels once the controller has ended.
"""
from __future__ import annotations

import http.client
import json
import queue
import re
import socket
import threading
import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Callable
from urllib.parse import urlsplit

#: Quick services that never answer 409 (attributes and functions): the flood cycles through them.
SERVICES = [("NDD", "SetSpeed"), ("NDD", "SetParams"), ("Aspect", "SetParams"), ("LaserRF", "SetConfig"),
            ("RFLEX", "SetAcceleration"), ("NDD", "SetDataSource")]
GONE = (ConnectionRefusedError, ConnectionResetError, BrokenPipeError, http.client.RemoteDisconnected,
        http.client.IncompleteRead, OSError)


@dataclass
class Seen:
    """What the clients saw, channel by channel."""

    sent_202: set[int] = field(default_factory=set)  # accepted, answered at once
    answers: dict[int, bool] = field(default_factory=dict)  # POST ?wait: id -> the answer carried a final report
    answers_cut: int = 0  # POST ?wait sent, its connection cut before any answer
    polls: dict[int, bool] = field(default_factory=dict)  # long poll in progress: id -> it ended with a final report
    queued: set[int] = field(default_factory=set)  # "queued" reports on /events
    finals: Counter = field(default_factory=Counter)  # final reports on /events, by request
    refused: Counter = field(default_factory=Counter)  # 4xx/5xx answers by status
    stream_ended: bool = False  # /events ended by itself (after the controller's last event)
    controller_event: dict | None = None  # the stream's "controller" event (the run ended)


@dataclass
class Missing:
    """Accepted requests without their final report, per channel; ``lost``: without one on any channel."""

    accepted: int
    lost: int
    answers: int
    polls: int
    events: int
    console: int
    duplicated: int
    lost_ids: tuple[int, ...] = ()  # the lost requests, to look up in the controller's output

    def line(self) -> str:
        lost = f" ({', '.join(map(str, self.lost_ids[:10]))})" if self.lost_ids else ""
        return (f"{self.accepted} accepted; lost {self.lost}{lost}; final reports missing: answers {self.answers}, "
                f"long polls {self.polls}, /events {self.events}, console {self.console}; "
                f"duplicated {self.duplicated}")


class Flood:
    """The flood; :meth:`run` returns once every client has sent its share and every poll has ended."""

    def __init__(self, url: str, requests: int = 2000, clients: int = 8, pollers: int = 8, wait_every: int = 2,
                 on_accepted: tuple[int, Callable[[], None]] | None = None, timeout: float = 90.0,
                 first_id: int = 1, read_delay: float = 0.0, rcvbuf: int | None = None,
                 answer_wait: float = 60.0) -> None:
        parts = urlsplit(url)
        self.host, self.port = parts.hostname, parts.port
        self.requests, self.clients, self.pollers = requests, clients, pollers
        self.wait_every = wait_every  # one request in wait_every waits for its answer
        self.first_id = first_id  # requests before it were sent before the flood: not counted
        self.answer_wait = answer_wait  # ?wait= of the requests that wait for their answer (s)
        self.read_delay = read_delay  # the /events listener takes this long over each event (a slow reader)
        self.rcvbuf = rcvbuf  # the /events listener's receive buffer (bytes), small for a reader on a slow link
        self.reading = threading.Event()  # cleared: the /events listener stops reading until it is set
        self.reading.set()
        self.on_accepted = on_accepted
        self.timeout = timeout
        self.seen = Seen()
        self._lock = threading.Lock()
        self._polls: queue.Queue = queue.Queue()
        self._accepted = 0
        self._fired = False
        self.stopping = threading.Event()  # the controller refused with 503 or went away: clients end
        self.listening = threading.Event()
        self._listener = threading.Thread(target=self._listen, daemon=True)

    # -- the run ---------------------------------------------------------------------------------------
    def start_listening(self) -> None:
        """Open /events (before the flood, so that every report of the flood is on it)."""
        self._listener.start()
        assert self.listening.wait(30), "/events did not answer"

    def run(self) -> Seen:
        if not self._listener.is_alive():
            self.start_listening()
        senders = [threading.Thread(target=self._send, args=(k,), daemon=True) for k in range(self.clients)]
        pollers = [threading.Thread(target=self._poll, daemon=True) for _ in range(self.pollers)]
        for t in senders + pollers:
            t.start()
        for t in senders:
            t.join(self.timeout)
        for _ in pollers:
            self._polls.put(None)
        for t in pollers:
            t.join(self.timeout)
        return self.seen

    def close(self) -> None:
        """Stop listening to /events (the flood is over)."""
        conn = getattr(self, "_listening_on", None)
        if conn is not None and conn.sock is not None:
            conn.sock.shutdown(socket.SHUT_RDWR)

    def join_listener(self, timeout: float = 30.0) -> None:
        """Wait for /events to end (the controller stopped)."""
        self._listener.join(timeout)

    def _accepted_one(self) -> None:
        with self._lock:
            self._accepted += 1
            fire = self.on_accepted is not None and not self._fired and self._accepted >= self.on_accepted[0]
            self._fired = self._fired or fire
        if fire:
            self.on_accepted[1]()

    def _connection(self) -> http.client.HTTPConnection:
        return http.client.HTTPConnection(self.host, self.port, timeout=self.timeout)

    def _send(self, k: int) -> None:
        """Client ``k``: its share of the requests, one in two waiting for its answer."""
        conn = self._connection()
        for i in range(k, self.requests, self.clients):
            if self.stopping.is_set():
                return
            component, service = SERVICES[i % len(SERVICES)]
            wait = i % self.wait_every == 0
            path = f"/components/{component}/services/{service}" + (f"?wait={self.answer_wait:g}" if wait else "")
            try:
                conn.request("POST", path, body=b"{}", headers={"Content-Type": "application/json"})
            except GONE:
                self.stopping.set()
                return
            try:
                response = conn.getresponse()
                body = json.loads(response.read() or b"null")
            except GONE:
                with self._lock:
                    self.seen.answers_cut += wait
                self.stopping.set()
                return
            if response.status >= 400:
                with self._lock:
                    self.seen.refused[response.status] += 1
                if response.status == 503:
                    self.stopping.set()
                    return
                continue
            self._accepted_one()
            with self._lock:
                if wait:
                    self.seen.answers[body["id"]] = body.get("final") is not None
                else:
                    self.seen.sent_202.add(body["id"])
            if not wait:
                self._polls.put(body["id"])

    def _poll(self) -> None:
        """A poller: long-polls each 202 request until its final report; a poll that could not start is not counted.

        A poll sent on a kept-alive connection the server closed meanwhile (it closes idle ones when it stops)
        gets no answer at all: it is sent once more on a new connection, as HTTP clients do for a GET.
        """
        conn = self._connection()
        while True:
            rid = self._polls.get()
            if rid is None:
                return
            for attempt in (1, 2):
                try:
                    conn.request("GET", f"/requests/{rid}?wait=60")
                    response = conn.getresponse()
                    body = json.loads(response.read() or b"null")
                    ended = response.status == 200 and body.get("final") is not None
                except (http.client.RemoteDisconnected, ConnectionResetError, BrokenPipeError):
                    conn.close()
                    conn = self._connection()
                    if attempt == 1:
                        continue
                    ended = False
                except ConnectionRefusedError:
                    conn.close()
                    conn = self._connection()
                    ended = None  # the server has gone: this poll was never asked
                except GONE + (http.client.HTTPException,):
                    conn.close()
                    conn = self._connection()
                    ended = False
                break
            if ended is not None:
                with self._lock:
                    self.seen.polls[rid] = ended

    def _listen(self) -> None:
        """/events, all along: queued and final reports by request, and the controller's last event."""
        conn = self._connection()
        if self.rcvbuf:
            conn.sock = socket.socket()
            conn.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, self.rcvbuf)
            conn.sock.connect((self.host, self.port))
        conn.request("GET", "/events")  # every kind: poster writes (laser scans) too
        self._listening_on = conn
        response = conn.getresponse()
        self.listening.set()
        data = None
        try:
            for raw in iter(response.readline, b""):
                line = raw.decode().rstrip("\r\n")
                if line.startswith("data:"):
                    data = json.loads(line[5:])
                elif line == "" and data is not None:
                    self._heard(data)
                    data = None
                    self.reading.wait()
                    if self.read_delay:
                        time.sleep(self.read_delay)
            self.seen.stream_ended = True
        except GONE:
            pass

    def _heard(self, event: dict) -> None:
        with self._lock:
            if event.get("event") == "report":
                if event["status"] == "queued":
                    self.seen.queued.add(event["request"])
                if event["final"]:
                    self.seen.finals[event["request"]] += 1
            elif event.get("event") == "controller":
                self.seen.controller_event = event

    # -- what is missing -----------------------------------------------------------------------------
    def missing(self, out: str) -> Missing:
        """Compare the channels once the controller has ended and printed ``out`` (its console and summary)."""
        s = self.seen
        first = self.first_id
        console = Counter(int(m) for m in re.findall(r"^\[(\d+)\] ", out, re.M) if int(m) >= first)
        summary = re.search(r"^stopped after \d+ steps; requests: ([^;\n]*)", out, re.M)
        total = sum(int(n) for n in re.findall(r"(\d+) \w+", summary.group(1))) - (first - 1) if summary else 0
        accepted = s.sent_202 | set(s.answers) | {rid for rid in s.queued if rid >= first}
        total = max(total, len(accepted))
        answered = {rid for rid, final in s.answers.items() if final}
        polled = {rid for rid, final in s.polls.items() if final}
        finals = {rid for rid in s.finals if rid >= first}
        anywhere = answered | polled | finals | set(console)
        answers_missing = (total - len(s.sent_202) - len(answered))
        dup = sum(n - 1 for n in s.finals.values() if n > 1) + sum(n - 1 for n in console.values() if n > 1)
        return Missing(accepted=total, lost=len(accepted - anywhere) + max(0, total - len(accepted)),
                       answers=answers_missing, polls=sum(1 for f in s.polls.values() if not f),
                       events=len(accepted - finals), console=len(accepted - set(console)), duplicated=dup,
                       lost_ids=tuple(sorted(accepted - anywhere)))
