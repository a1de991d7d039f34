"""Bad requests that were taken for good ones: a number for a string in the ids, a request id read loosely."""
from __future__ import annotations

import copy
import json
import sys
import urllib.error
import urllib.parse
import urllib.request

import pytest

from badinputkit import ROOT

sys.path.insert(0, str(ROOT / "tests"))
from runkit import build, serving_dala  # noqa: E402

pytestmark = pytest.mark.reliability

NAMED = """
component m {
  ids { struct cfg_s { string<16> name; double gain; long count; } cfg; };
  attribute SetName(in cfg.name);
  attribute SetGain(in cfg.gain);
  attribute SetCount(in cfg.count);
};
"""


def _controller(tmp_path, edit=None):
    from runtime.controller import Controller, VirtualClock

    package, root, interface = build(tmp_path, NAMED, "m")
    if edit is not None:
        interface = copy.deepcopy(interface)
        edit(interface)
    return Controller(package, root, interface, {}, clock=VirtualClock())


@pytest.mark.parametrize("service, inputs, message", [
    ("SetName", {"name": 5}, "name: expected a string, got 5"),
    ("SetGain", {"gain": "fast"}, "gain: expected a number, got 'fast'"),
    ("SetCount", {"count": 2.5}, "count: expected an integer, got 2.5"),
])
def test_an_input_bound_to_a_member_of_a_named_struct_is_checked_against_its_type(tmp_path, service, inputs,
                                                                                   message):
    from runtime.controller import RequestError

    c = _controller(tmp_path)
    with pytest.raises(RequestError) as err:
        c.submit("m", service, inputs)
    assert err.value.status == 422 and message in err.value.message, err.value.message
    assert c.data.ids["m"]["cfg"] == {"name": "", "gain": 0.0, "count": 0}
    assert c.submit("m", "SetName", {"name": "arm"}).inputs == {"name": "arm"}


def test_a_package_whose_schema_says_nothing_still_keeps_a_string_member_a_string(tmp_path):
    """A package generated before member paths had a schema: the ids keep their kinds all the same."""
    from runtime.controller import RequestError

    def forget(interface):
        for service in interface["components"]["m"]["services"].values():
            for p in service["parameters"]:
                p["schema"] = {}

    c = _controller(tmp_path, forget)
    with pytest.raises(RequestError) as err:
        c.submit("m", "SetName", {"name": 5})
    assert err.value.status == 422
    assert "parameter 'name' cannot be stored in ids member cfg.name: it holds a string, not a number (5)" \
        in err.value.message
    with pytest.raises(RequestError) as err:
        c.submit("m", "SetCount", {"count": 2.5})
    assert "it holds an integer, not 2.5" in err.value.message
    assert c.submit("m", "SetGain", {"gain": 3}).inputs == {"gain": 3}  # an integer is a number


def _get(url: str) -> tuple[int, str]:
    try:
        with urllib.request.urlopen(url, timeout=30) as answer:
            return answer.status, answer.read().decode()
    except urllib.error.HTTPError as err:
        return err.code, err.read().decode()


@pytest.mark.parametrize("written", ["1_0", "+10", " 10", "10 ", "010", "\u0661\u0660", "1e1", "-10"])
def test_a_request_id_is_read_exactly_or_refused(written):
    with serving_dala() as (controller, server, client):
        for _ in range(10):
            client.send("NDD", "SetSpeed", {})
        assert _get(f"{server.url}/requests/10")[0] == 200
        status, body = _get(f"{server.url}/requests/{urllib.parse.quote(written)}")
        assert status == 400, body
        assert json.loads(body)["error"].startswith(f"request id {written!r} is not a number as the server writes "
                                                    "them (digits 0-9, no sign, no leading zero)")


def test_a_limit_in_another_script_is_refused_not_a_server_error():
    with serving_dala() as (controller, server, client):
        status, body = _get(f"{server.url}/requests?limit={urllib.parse.quote(chr(0xB2))}")
        assert status == 400 and "a number of requests from 1 to 999999999 expected" in body
