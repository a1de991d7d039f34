"""The generated controller at run time: real periods, Python codels, posters and requests with reports.

``Controller(package, root, interface, codels)`` runs the engine in a thread
of its own (``start``/``stop``) and takes requests from any thread
(``submit``, ``wait``); docs/runtime.md describes the semantics.
"""
from runtime.controller.controller import Controller
from runtime.controller.meaning import StepInfo
from runtime.controller.requests import FINAL, REPORT_STATUSES, REQUEST_STATUSES, Request, RequestError
from runtime.controller.timing import MonotonicClock, VirtualClock

__all__ = ["FINAL", "REPORT_STATUSES", "REQUEST_STATUSES", "Controller", "MonotonicClock", "Request", "RequestError",
           "StepInfo", "VirtualClock"]
