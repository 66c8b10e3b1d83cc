"""Attacks on the web catalogue (/ui): forged and stolen cookies, sign-in and forms without
CSRF, hostile page parameters with a real session; and the session a browser gets by
signing in through the form (whatever hidden fields the form carries)."""

from __future__ import annotations

import re
from urllib.parse import urlencode

import httpx

from security_run import Attack

COOKIE = "jointdb_session"
FORM = [("Content-Type", "application/x-www-form-urlencoded")]


def hidden_fields(html: str, action: str) -> dict[str, str]:
    """The hidden inputs of the form posting to ``action``."""
    for form in re.findall(r"<form\b[^>]*>.*?</form>", html, re.S | re.I):
        if f'action="{action}"' in form:
            return dict(re.findall(r'<input[^>]*type="hidden"[^>]*name="([^"]+)"[^>]*value="([^"]*)"', form, re.I)
                        + re.findall(r'<input[^>]*name="([^"]+)"[^>]*type="hidden"[^>]*value="([^"]*)"', form, re.I))
    return {}


def sign_in(url: str, token: str) -> str | None:
    """Sign in through the form as a browser does; the Cookie header of the session (or None)."""
    with httpx.Client(base_url=url, timeout=30.0, follow_redirects=False) as c:
        page = c.get("/ui/signin")
        fields = {**hidden_fields(page.text, "/ui/signin"), "token": token}
        r = c.post("/ui/signin", content=urlencode(fields), headers=dict(FORM))
        if r.status_code not in (302, 303) or "/ui/signin" in r.headers.get("location", ""):
            return None
        return "; ".join(f"{ck.name}={ck.value}" for ck in c.cookies.jar) or None


def session_csrf(url: str, cookie: str, page: str, action: str) -> dict[str, str]:
    with httpx.Client(base_url=url, timeout=30.0) as c:
        return hidden_fields(c.get(page, headers={"Cookie": cookie}).text, action)


def web(target, cookie: str | None) -> list[Attack]:
    a = target.joints["writer"]
    tok = target.tokens
    out = [Attack("web sessions", "API token used as the session cookie", "GET", "/ui/joints", None,
                  [("Cookie", f"{COOKIE}={tok['writer']}")], expect="refused"),
           Attack("web sessions", "revoked token as the session cookie", "GET", "/ui/joints", None,
                  [("Cookie", f"{COOKIE}={tok['revoked']}")], expect="refused"),
           Attack("web sessions", "forged cookie", "GET", "/ui/joints", None,
                  [("Cookie", f"{COOKIE}=jdb_000000000000_forged")], expect="refused"),
           Attack("web sessions", "sign-in without CSRF", "POST", "/ui/signin", None, FORM,
                  urlencode({"token": tok["reader"]}).encode(), expect="refused"),
           Attack("web sessions", "sign-in without CSRF, cross-site", "POST", "/ui/signin", None,
                  FORM + [("Origin", "https://evil.example"), ("Referer", "https://evil.example/x")],
                  urlencode({"token": tok["writer"], "csrf": "x"}).encode(), expect="refused")]
    for action, form in (("label", {"version": "1", "label": "csrf"}), ("deprecate", {"version": "1", "reason": "x"})):
        out.append(Attack("web sessions", f"{action} form with the token cookie and no CSRF", "POST",
                          f"/ui/joints/{a}/{action}", None, FORM + [("Cookie", f"{COOKIE}={tok['writer']}")],
                          urlencode(form).encode(), expect="refused"))
    if cookie is None:
        return out
    c = [("Cookie", cookie)]
    tampered = cookie[:-1] + ("A" if cookie[-1] != "A" else "B")
    out.append(Attack("web sessions", "tampered session cookie", "GET", "/ui/joints", None, [("Cookie", tampered)],
                      expect="refused"))
    for action, form in (("label", {"version": "1", "label": "csrf"}), ("deprecate", {"version": "1", "reason": "x"})):
        for what, extra in (("no CSRF", {}), ("wrong CSRF", {"csrf": "0" * 64})):
            out.append(Attack("web sessions", f"{action} form, {what}", "POST", f"/ui/joints/{a}/{action}", None,
                              FORM + c, urlencode({**form, **extra}).encode(), expect="refused"))
    pages = ["/ui/joints?offset=-1", "/ui/joints?offset=99999999999999999999", "/ui/joints?torque_min=nan",
             "/ui/joints?torque_min=abc", "/ui/joints?torque_max=1e400", "/ui/joints?q=%00", "/ui/joints?type=%00",
             "/ui/joints?material=%00", f"/ui/joints/{a}?version=%00", f"/ui/joints/{a}?version=99",
             f"/ui/joints/{a}?version=99999999999999999999", "/ui/joints/%00", "/ui/joints/..%2f..%2fetc%2fpasswd",
             f"/ui/joints/{a}/overlay?a=1&b=999", f"/ui/joints/{a}/overlay?a=x&b=1", f"/ui/joints/{a}/overlay?a=-1&b=1",
             "/ui/nearest?joint_type=%00&torque_nm=1", "/ui/nearest?joint_type=tool-holder&torque_nm=nan",
             "/ui/nearest?joint_type=tool-holder&torque_nm=1e400&k=-1", "/ui/nearest?joint_type=tool-holder&k=999",
             f"/ui/joints/{a}/versions/1/frf?format=../../etc/passwd", f"/ui/joints/{a}/versions/99999999999999999999/frf",
             f"/ui/joints/{a}?notice=%3Cscript%3Ealert(1)%3C/script%3E", "/ui/static/..%2f_app.py",
             "/ui/static/%2e%2e/_settings.py", f"/ui/joints/{a}/unknown-action"]
    for p in pages:
        out.append(Attack("web pages", f"page {p[:50]}", "GET", p, None, c, expect="ok"))
    out.append(Attack("web pages", "form to an unknown action", "POST", f"/ui/joints/{a}/drop", None, FORM + c,
                      b"csrf=x", expect="refused"))
    return out
