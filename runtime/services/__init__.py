"""The services interface of a running controller: HTTP/JSON server (Starlette on uvicorn) and Python client."""
from runtime.services.client import Client, ServiceError, parse_target

__all__ = ["Client", "ServiceError", "parse_target"]
