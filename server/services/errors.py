"""The errors services raise, each with the HTTP status the app answers it with (`server.app`).

A service never knows about HTTP: it raises `NotFound("no recording ...")`, and the app's
exception handler turns it into ``{"detail": "no recording ..."}`` with status 404.
"""

from __future__ import annotations


class ServiceError(Exception):
    """A request a service cannot answer, with a message the user can act on."""

    status = 500


class NotFound(ServiceError, LookupError):
    status = 404


class Invalid(ServiceError, ValueError):
    status = 422


class Conflict(ServiceError):
    status = 409


class TooLarge(ServiceError):
    status = 413


class Unavailable(ServiceError):
    status = 503
