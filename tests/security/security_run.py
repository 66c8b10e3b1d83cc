"""The attack model, the runner and the checks of the security suite.

An :class:`Attack` is one hostile request with what it may get back: ``"4xx"`` (refused),
``"ok"`` (any answer below 500: accepted or refused, the request is legitimate in form),
``"refused"`` (4xx or a redirect to the sign-in page) or ``"4xx|closed"`` (malformed HTTP:
refused or the connection closed). Whatever it expects, no attack may get a 5xx, and no
answer may carry a secret of the server (see :func:`leaks`).
"""

from __future__ import annotations

import json
import re
import socket
import time
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import unquote, urlsplit

import httpx

_NO = object()


@dataclass
class Attack:
    cls: str  # the hostile class (reported per class)
    what: str  # one line naming the request
    method: str = "GET"
    path: str = "/"
    role: str | None = "reader"  # whose bearer token is sent (None: none)
    headers: list[tuple[str, str]] = field(default_factory=list)
    content: bytes | None = None
    expect: str = "4xx"
    raw: bytes | None = None  # a raw HTTP/1.1 request written to a socket instead
    echo: str = ""  # what else the attacker sent (text of archive members): reflecting it is no leak

    def sent_text(self) -> str:
        body = (self.content or b"")[:200_000].decode("utf-8", "replace")
        raw = (self.raw or b"")[:200_000].decode("latin-1")
        return " ".join([self.path, unquote(self.path), *(f"{k}: {v}" for k, v in self.headers), body, raw,
                         unquote(raw), self.echo])


@dataclass
class Result:
    attack: Attack
    status: int  # 0: connection closed / no answer
    headers: str
    body: str
    seconds: float

    def expected(self) -> bool:
        s, e = self.status, self.attack.expect
        if 500 <= s or (s == 0 and not e.endswith("|closed")):
            return False
        if e == "ok":
            return True
        if e == "refused":
            return 400 <= s < 500 or (300 <= s < 400 and "/ui/signin" in self.headers)
        if e == "4xx|closed":
            return s == 0 or 400 <= s < 500
        if e == "ok|closed":
            return True
        if e == "2xx":
            return 200 <= s < 300
        return 400 <= s < 500

    def line(self) -> str:
        a = self.attack
        excerpt = " ".join(self.body[:160].split())
        return f"[{a.cls}] {a.what}: {a.method} {a.path[:90]} as {a.role} -> {self.status} {excerpt!r}"


def json_body(obj: Any) -> bytes:
    """JSON with NaN/Infinity literals allowed (they are part of the attacks)."""
    return json.dumps(obj, allow_nan=True).encode()


JSON = [("Content-Type", "application/json")]


def _raw(url: str, data: bytes, timeout: float = 5.0) -> tuple[int, str, str]:
    parts = urlsplit(url)
    with socket.create_connection((parts.hostname, parts.port), timeout=timeout) as s:
        try:
            s.sendall(data)
        except OSError:
            pass  # the server may close early; read what it said
        chunks = []
        try:
            while True:
                chunk = s.recv(65536)
                if not chunk:
                    break
                chunks.append(chunk)
                got = b"".join(chunks)
                head, sep, rest = got.partition(b"\r\n\r\n")
                m = re.search(rb"(?i)\r\ncontent-length:\s*(\d+)", head)
                if sep and (len(got) > 2**20 or (m and len(rest) >= int(m.group(1)))):
                    break  # a whole answer: do not wait for a keep-alive connection to close
        except OSError:
            pass
    text = b"".join(chunks).decode("latin-1")
    m = re.match(r"HTTP/1\.[01] (\d{3})", text)
    head, _, body = text.partition("\r\n\r\n")
    return (int(m.group(1)) if m else 0), head, body


def run(target, attacks: list[Attack]) -> list[Result]:
    """Send every attack in order over one keep-alive client (raw ones over their own socket)."""
    out = []
    with httpx.Client(base_url=target.url, timeout=60.0, follow_redirects=False) as client:
        for a in attacks:
            t0 = time.perf_counter()
            if a.raw is not None:
                status, head, body = _raw(target.url, a.raw)
                out.append(Result(a, status, head, body, time.perf_counter() - t0))
                continue
            headers = list(a.headers)
            if a.role and not any(k.lower() == "authorization" for k, _ in headers):
                headers.append(("Authorization", f"Bearer {target.tokens[a.role]}"))
            for attempt in (1, 2):  # once more on a fresh connection if the server closed the kept-alive one
                try:
                    r = client.request(a.method, a.path, content=a.content, headers=headers)
                    head = "\n".join(f"{k}: {v}" for k, v in r.headers.multi_items())
                    out.append(Result(a, r.status_code, head, r.text, time.perf_counter() - t0))
                    break
                except (httpx.ReadError, httpx.RemoteProtocolError, httpx.WriteError) as exc:
                    if attempt == 2:
                        out.append(Result(a, 0, "", f"{type(exc).__name__}: {exc}", time.perf_counter() - t0))
                except httpx.HTTPError as exc:
                    out.append(Result(a, 0, "", f"{type(exc).__name__}: {exc}", time.perf_counter() - t0))
                    break
    return out


# what a server never says, whoever asks (checked only where the attacker did not send it)
GENERIC_MARKERS = {
    "/etc/passwd contents": "root:x:0:0", "a Python traceback": "Traceback (most recent call last)",
    "a source line of a traceback": 'File "/', "a path under /etc": "/etc/", "a path under /root": "/root/",
    "a path under /home": "/home/", "a path under /proc": "/proc/", "a PostgreSQL URL": "postgresql://",
    "a SQLAlchemy PostgreSQL URL": "postgresql+psycopg", "an SQLite URL": "sqlite:///",
    "an environment variable": "JOINTDB_TEST_PG_URL",
}


def leaks(text: str, secrets: dict[str, str], echo: str = "") -> list[str]:
    """The secrets (and generic markers) in ``text`` that the attacker did not send itself;
    a token is a leak even when it was sent."""
    found = []
    for what, value in {**secrets, **GENERIC_MARKERS}.items():
        if not value or len(value) < 6 or value not in text:
            continue
        if "token" not in what and value in echo:
            continue
        found.append(what)
    return found


def response_leaks(results: list[Result], secrets: dict[str, str]) -> list[str]:
    out = []
    for r in results:
        found = leaks(r.headers + "\n" + r.body, secrets, r.attack.sent_text())
        if found:
            at = min(i for i in ((r.headers + "\n" + r.body).find(secrets.get(w, GENERIC_MARKERS.get(w, "")))
                                 for w in found) if i >= 0)
            excerpt = (r.headers + "\n" + r.body)[max(0, at - 60):at + 80]
            out.append(f"{r.line()}\n      leaks {', '.join(found)}: ...{' '.join(excerpt.split())}...")
    return out


#: what no log line may carry (a traceback may name the package's files; tokens, the database URL and
#: file contents never)
LOG_SECRETS = ("token", "database", "search_path")
LOG_MARKERS = ("/etc/passwd contents", "an environment variable")


def log_problems(text: str, secrets: dict[str, str]) -> tuple[list[str], list[str], list[str]]:
    """(lines that are not one JSON object, lines that leak a secret, request lines with status 0 or 5xx).

    The start-up line may name the database (without credentials); server directories are
    allowed only in a traceback (which the failure check reports anyway)."""
    not_json, leaking, bad_status = [], [], []
    for n, line in enumerate(text.splitlines(), 1):
        obj = None
        try:
            obj = json.loads(line)
        except ValueError:
            pass
        if not isinstance(obj, dict):
            not_json.append(f"line {n}: {line[:160]}")
        startup = '"startup"' in line  # it may name the database the operator configured (no credentials)
        traceback = "Traceback" in line or 'File "' in line

        def applies(what: str) -> bool:
            if "token" in what:
                return True
            return not startup and (any(w in what for w in LOG_SECRETS) or not traceback)

        check = {k: v for k, v in secrets.items() if applies(k)}
        found = [w for w in leaks(line, check) if w in check or w in LOG_MARKERS]
        if found:
            leaking.append(f"line {n} leaks {', '.join(found)}: {line[:200]}")
        if isinstance(obj, dict) and obj.get("event") == "request" and not (0 < int(obj.get("status") or 0) < 500):
            bad_status.append(f"line {n}: {line[:200]}")
    return not_json, leaking, bad_status


def first(lines: list[str], n: int = 8) -> str:
    more = f"\n  ... and {len(lines) - n} more" if len(lines) > n else ""
    return "\n  " + "\n  ".join(lines[:n]) + more


def per_class(results: list[Result], pred) -> dict[str, str]:
    """``{class: "bad/total"}`` for the classes where ``pred`` is true for some result."""
    total: dict[str, int] = {}
    bad: dict[str, int] = {}
    for r in results:
        total[r.attack.cls] = total.get(r.attack.cls, 0) + 1
        if pred(r):
            bad[r.attack.cls] = bad.get(r.attack.cls, 0) + 1
    return {c: f"{bad[c]}/{total[c]}" for c in bad}
