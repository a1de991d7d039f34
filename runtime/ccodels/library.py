"""A component's C codels as the controller's codel functions: one shared library per component, bound by ctypes.

The library is loaded with RTLD_LOCAL (codel names collide between components).  Each codel becomes a
Python function with the keyword arguments a Python codel gets (runtime/controller/binding.py), so the
controller calls C and Python codels the same way: ``in`` values are copied into C data, ``out``/``inout``
holders too and read back after the call, ports are handles whose ``data()`` points at a copy of the
poster (``write()`` publishes it), and the context's ``raise()`` records an exception and its detail,
decoded by the exception's IDL type and thrown as :class:`~runtime.genom.Throw`.  The returned event
(``::comp::pause::main``) is the yield name (``pause::main``).
"""
from __future__ import annotations

import ctypes
import os
import time
from pathlib import Path
from typing import Any, Callable

from runtime.ccodels.marshal import Layouts
from runtime.genom import Ref, Throw

EVENT = ctypes.c_void_p  # a genom_event (const char *), NULL for genom_ok
RAISE = ctypes.CFUNCTYPE(EVENT, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p)
RAISED = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.POINTER(ctypes.c_void_p), ctypes.c_void_p)
NOW = ctypes.CFUNCTYPE(ctypes.c_double, ctypes.c_int)  # genom2bip_now(realtime): runtime/ccodels/clock
DEVICE = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_char_p)  # genom2bip_devices(name): runtime/ccodels/devices


class Context(ctypes.Structure):
    """``struct genom_context_iface``: raise, raised, data."""

    _fields_ = [("raise_", RAISE), ("raised", RAISED), ("data", ctypes.c_void_p)]


class CodelLibraryError(Exception):
    """The library cannot be loaded or lacks a codel: said with the library's path."""


class Raised:
    """What a codel raised through its context: the exception id and a copy of its detail."""

    def __init__(self) -> None:
        self.event: int | None = None
        self.detail = b""
        self.plain: dict[str, Any] = {}  # the detail as plain data, when a remote answered the exception
        self.raise_ = RAISE(self._raise)
        self.raised = RAISED(self._raised)
        self.context = Context(self.raise_, self.raised, None)
        self._buffer: Any = None

    def _raise(self, ex: int | None, detail: int | None, size: int, _self: int | None) -> int | None:
        self.event, self.plain = ex, {}
        self.detail = ctypes.string_at(detail, size) if detail and size else b""
        return ex

    def _raised(self, ex: Any, _self: int | None) -> int | None:
        if ex:
            ex[0] = self.event
        if not self.detail:
            return None
        self._buffer = ctypes.create_string_buffer(self.detail, len(self.detail))
        return ctypes.addressof(self._buffer)


_HANDLES: dict[tuple[bool, bool], Any] = {}
#: What ``read()`` returns while the poster a port reads was never written: an event no codel declares.
NO_DATA = ctypes.create_string_buffer(b"::genom2bip::no_data")
NO_DATA_EVENT = ctypes.addressof(NO_DATA)


def _handle_type(multiple: bool, out: bool) -> Any:
    """The ctypes structure of a port handle (made once per kind): data, read or write, open and close."""
    key = (multiple, out)
    if key not in _HANDLES:
        voidp, chars = ctypes.c_void_p, ctypes.c_char_p
        if multiple:
            fields = [("data", ctypes.CFUNCTYPE(voidp, chars, voidp)), ("rw", ctypes.CFUNCTYPE(EVENT, chars, voidp))]
            if out:
                fields += [("open", ctypes.CFUNCTYPE(EVENT, chars, voidp)),
                           ("close", ctypes.CFUNCTYPE(EVENT, chars, voidp))]
        else:
            fields = [("data", ctypes.CFUNCTYPE(voidp, voidp)), ("rw", ctypes.CFUNCTYPE(EVENT, voidp))]
        _HANDLES[key] = type("port_handle", (ctypes.Structure,), {"_fields_": fields})
    return _HANDLES[key]


class Port:
    """A port handle for one call: ``data()`` points at a C copy of the poster's value, ``write()`` marks it."""

    def __init__(self, layouts: Layouts, lay: list, direction: str, multiple: bool, value: Any) -> None:
        self.layouts, self.lay, self.multiple = layouts, lay, multiple
        self.out = direction != "in"
        self.keep: list = []
        self.buffers: dict[str | None, Any] = {}
        self.written: set[str | None] = set()
        self.closed: set[str] = set()
        self.initial = value
        handle = _handle_type(multiple, self.out)
        types = dict(handle._fields_)
        if multiple:
            calls = [types["data"](lambda i, s: self.data(i.decode())), types["rw"](lambda i, s: self.mark(i.decode()))]
            if self.out:
                calls += [types["open"](lambda i, s: self.open(i.decode())),
                          types["close"](lambda i, s: self.close(i.decode()))]
        else:
            calls = [types["data"](lambda s: self.data(None)), types["rw"](lambda s: self.mark(None))]
        self.calls = calls
        self.handle = handle(*calls)

    def _value_of(self, key: str | None) -> Any:
        if key is None:
            return self.initial
        return self.initial.get(key) if isinstance(self.initial, dict) else None

    def data(self, key: str | None) -> int:
        if key not in self.buffers:
            lay = self.lay
            if lay[0] == "str" and lay[1] is None:  # an unbounded string: data() gives the char * itself
                holder = ctypes.c_char_p(str(self._value_of(key) or "").encode())
            else:
                holder = self.layouts.new(lay, self._value_of(key), self.keep)
            self.buffers[key] = holder
        return ctypes.addressof(self.buffers[key])

    def mark(self, key: str | None) -> int | None:
        """``write()`` publishes the element after the call; ``read()`` fails while the poster holds nothing."""
        if self.out:
            self.data(key)
            self.written.add(key)
            return None
        return NO_DATA_EVENT if self._value_of(key) is None else None

    def open(self, key: str) -> None:
        self.closed.discard(key)
        self.data(key)
        return None

    def close(self, key: str) -> None:
        self.closed.add(key)
        return None

    def published(self) -> tuple[bool, Any]:
        """(written, the value to publish) after the call."""
        if not self.written and not self.closed:
            return False, None
        if not self.multiple:
            return True, self.layouts.value(self.lay, self.buffers[None])
        now = dict(self.initial) if isinstance(self.initial, dict) else {}
        for key in self.written:
            now[key] = self.layouts.value(self.lay, self.buffers[key])
        for key in self.closed:
            now.pop(key, None)
        return True, now


class RemoteHandle:
    """A remote's handle for the C codels: ``call(params..., self)`` converts its arguments to plain values, calls
    the controller's remote (:class:`runtime.controller.remote.Remote`), writes the outputs back and returns
    ``genom_ok`` or the exception's id (its detail given to the context, as ``raise()`` would)."""

    def __init__(self, library: "CodelLibrary", name: str, params: list[list]) -> None:
        self.library, self.name, self.params = library, name, params
        layouts = library.layouts
        types = [layouts.ctype(lay) if d == "in" and layouts.is_scalar(lay) else ctypes.c_void_p for d, lay in params]
        self.kind = ctypes.CFUNCTYPE(EVENT, *types, ctypes.c_void_p)
        self.struct = type(f"remote_{name}", (ctypes.Structure,), {"_fields_": [("call", self.kind)]})

    def bind(self, remote: Any, raised: "Raised", keep: list) -> Any:
        """The handle for one codel call: ``remote`` is the controller's (None: no controller reaches it)."""
        layouts = self.library.layouts

        def call(*args: Any) -> int | None:
            try:
                inputs: dict[str, Any] = {}
                spec = getattr(remote, "parameters", None) or [{"name": f"arg{k}"} for k in range(len(self.params))]
                for (direction, lay), p, raw in zip(self.params, spec, args):
                    if direction == "out":
                        continue
                    if direction == "in" and layouts.is_scalar(lay):
                        inputs[p["name"]] = layouts.value(lay, raw)
                    else:
                        inputs[p["name"]] = layouts.value(lay, layouts.ctype(lay).from_address(raw))
                if remote is None:
                    raise Throw("genom::no_such_remote", what=f"remote {self.name} of {self.library.component} "
                                                              "is not reachable from here")
                outputs = remote(**inputs)
                for (direction, lay), p, raw in zip(self.params, spec, args):
                    if direction != "in" and p["name"] in outputs:
                        target = layouts.ctype(lay).from_address(raw)
                        if layouts.is_scalar(lay):
                            target.value = layouts.scalar(lay, outputs[p["name"]], keep)
                        else:
                            layouts.fill(lay, outputs[p["name"]], target, keep)
                return None
            except Throw as thrown:
                return self.library.raise_into(raised, thrown, keep)
            except Exception as err:  # noqa: BLE001 - said as the remote's failure, never through C
                return self.library.raise_into(raised, Throw("genom::remote_io", what=f"{type(err).__name__}: {err}"),
                                               keep)

        fn = self.kind(call)
        keep.append(fn)
        handle = self.struct(fn)
        keep.append(handle)
        return handle


class CodelLibrary:
    """The C codels of one component: ``find(name)`` gives the Python function that calls one."""

    def __init__(self, component: str, path: str | Path, spec: dict[str, Any]) -> None:
        self.component = component
        self.path = str(path)
        try:
            self.lib = ctypes.CDLL(self.path, mode=os.RTLD_LOCAL | os.RTLD_NOW)
        except OSError as err:
            raise CodelLibraryError(f"{self.path}: cannot load the C codels of {component}: {err}") from None
        self.layouts = Layouts(spec["types"])
        self.codels: dict[str, list] = spec["codels"]
        self.simple = set(spec.get("simple", ()))  # codels whose genom_ok is their one yield, ether
        self.exceptions: dict[str, list] = spec["exceptions"]
        self.prefix = f"::{component}::"
        self.remotes: dict[str, list] = spec.get("remotes", {})
        self._made: dict[str, Callable] = {}
        self._remotes: dict[str, RemoteHandle] = {}
        self._events: dict[str, Any] = {}

    def follow(self, clock: Any) -> bool:
        """Make the codels' wall clock (gettimeofday, clock_gettime, time) the controller's ``clock``."""
        try:
            hook = ctypes.c_void_p.in_dll(self.lib, "genom2bip_now")
        except ValueError:
            return False
        epoch = time.time() - clock.now()
        self._now = NOW(lambda realtime: clock.now() + (epoch if realtime else 0.0))  # kept alive here
        hook.value = ctypes.cast(self._now, ctypes.c_void_p).value
        return True

    def offer(self, devices: dict[str, Callable[[], Any]]) -> bool:
        """Give the codels ``devices`` (name -> a function making the device's table, a ctypes object, on first
        use): what ``genom2bip_device(name)`` returns them (genom2bip/device.h)."""
        try:
            hook = ctypes.c_void_p.in_dll(self.lib, "genom2bip_devices")
        except ValueError:
            return False
        made: dict[str, Any] = {}

        def device(name: bytes) -> int | None:
            key = name.decode(errors="replace")
            if key not in made:
                try:
                    made[key] = devices[key]() if key in devices else None
                except Exception:  # noqa: BLE001 - a device that cannot be made is none: the codel says so
                    made[key] = None
            return ctypes.addressof(made[key]) if made[key] is not None else None

        self._devices = DEVICE(device)  # kept alive here
        hook.value = ctypes.cast(self._devices, ctypes.c_void_p).value
        return True

    def get(self, name: str) -> Callable | None:
        """The function calling codel ``name``, None when the component declares no such C codel."""
        if name in self._made:
            return self._made[name]
        if name not in self.codels:
            return None
        try:
            symbol = getattr(self.lib, name)
        except AttributeError:
            return None
        symbol.restype = EVENT
        fn = self._caller(name, symbol, self.codels[name])
        self._made[name] = fn
        return fn

    def _caller(self, name: str, symbol: Any, args: list[list]) -> Callable:
        layouts = self.layouts
        simple = name in self.simple

        def codel(**kwargs: Any) -> str | None:
            keep: list = []
            raised = Raised()
            passed: list = []
            back: list[tuple[Ref, list, Any]] = []
            ports: list[tuple[Ref | None, Port]] = []
            for value, arg in zip(kwargs.values(), args):
                kind = arg[0]
                if kind == "port":
                    lay = arg[3]
                    holder = value if isinstance(value, Ref) else None
                    port = Port(layouts, lay, arg[1], arg[2], holder.value if holder is not None else value)
                    ports.append((holder, port))
                    passed.append(ctypes.byref(port.handle))
                elif kind == "remote":
                    handle = self.remote_handle(arg[1]).bind(value, raised, keep)
                    passed.append(ctypes.byref(handle))
                elif kind == "value":
                    lay = arg[1]
                    if layouts.is_scalar(lay):
                        obj = layouts.new(lay, value, keep)
                        passed.append(obj)
                    else:
                        obj = layouts.new(lay, value, keep)
                        keep.append(obj)
                        passed.append(ctypes.byref(obj))
                else:  # reference: out / inout
                    lay = arg[1]
                    current = value.value if isinstance(value, Ref) else value
                    obj = layouts.new(lay, current, keep)
                    keep.append(obj)
                    passed.append(ctypes.byref(obj))
                    if isinstance(value, Ref):
                        back.append((value, lay, obj))
            passed.append(ctypes.byref(raised.context))
            event = symbol(*passed)
            for ref, lay, obj in back:
                ref.value = layouts.value(lay, obj)
                layouts.release(lay, obj, keep)
            for holder, port in ports:
                written, now = port.published()
                if written and holder is not None:
                    holder.value = now
            if event is None:
                return "ether" if simple else None
            text = ctypes.string_at(event).decode(errors="replace")
            if raised.event is not None and raised.event == event or text in self.exceptions:
                if raised.plain and text not in self.exceptions:  # a remote's answer the component does not declare
                    raise Throw(text.removeprefix("::"), detail=raised.plain)
                self._throw(text, raised.detail)
            if text.startswith(self.prefix):
                return text[len(self.prefix):]
            return text

        codel.__name__ = name
        codel.__qualname__ = f"{self.component}.{name}"
        return codel

    def remote_handle(self, name: str) -> RemoteHandle:
        if name not in self._remotes:
            self._remotes[name] = RemoteHandle(self, name, self.remotes.get(name, []))
        return self._remotes[name]

    def event_id(self, name: str) -> int:
        """The address of the event ``::name``: the library's own ``<cname>_id`` when it has one (codels compare
        events by address), else a string of ours."""
        symbol = name.removeprefix("::").replace("::", "_") + "_id"
        try:
            return ctypes.addressof(ctypes.c_char.in_dll(self.lib, symbol))
        except ValueError:
            if name not in self._events:
                self._events[name] = ctypes.create_string_buffer(f"::{name.removeprefix('::')}".encode())
            return ctypes.addressof(self._events[name])

    def raise_into(self, raised: Raised, thrown: Throw, keep: list) -> int:
        """Give the codel's context the exception ``thrown`` (what a remote answered); its id, to return."""
        key = f"::{thrown.name.removeprefix('::')}"
        event = self.event_id(key)
        raised.event, raised.detail, raised.plain = event, b"", dict(thrown.detail)
        known = self.exceptions.get(key)
        if known is not None and known[1] is not None and thrown.detail:
            types = dict(self.layouts.types)
            types[f"{known[0]}::detail"] = known[1]
            writer = Layouts(types)
            obj = writer.new(["ref", f"{known[0]}::detail"], thrown.detail, keep)
            keep.append(obj)
            raised.detail = ctypes.string_at(ctypes.addressof(obj), ctypes.sizeof(obj))
        return event

    def _throw(self, text: str, detail: bytes) -> None:
        known = self.exceptions.get(text)
        if known is None:
            raise Throw(text.removeprefix("::"))
        name, lay = known
        members: dict[str, Any] = {}
        if lay is not None and detail:
            types = dict(self.layouts.types)
            types[f"{name}::detail"] = lay
            reader = Layouts(types)
            ctype = reader.ctype(["ref", f"{name}::detail"])
            obj = ctype.from_buffer_copy(detail.ljust(ctypes.sizeof(ctype), b"\0")[: ctypes.sizeof(ctype)])
            members = reader.value(["ref", f"{name}::detail"], obj)
        raise Throw(name, detail=members)
