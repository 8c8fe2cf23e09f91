"""Registries of plug-in parts, keyed by the names used in scenario files (docs/design.md, "Pluggable
parts").

One small class serves every kind: hole sections (:data:`flexmbs.contact.sections.HOLE_SECTIONS`),
contact laws (:data:`flexmbs.contact.laws.CONTACT_LAWS`) and the scenario builders of elements,
constraints, joints, loads and probes (:mod:`flexmbs.io.builders`). The Python API and the
scenario reader look names up in the same registry, so they accept the same list and fail with
the same message::

    HOLE_SECTIONS.get("hexagon")
    # ModelError: unknown hole section 'hexagon' (known: circle, rounded_rectangle, superellipse)

Names are listed in registration order (the order of the documentation).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar, overload

from .errors import ModelError

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(Generic[T]):
    """Name -> entry (a class or a builder function) of one kind of plug-in part.

    ``kind`` names the part in messages (``"hole section"``, ``"constraint type"``).
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._entries: dict[str, T] = {}

    @overload
    def register(self, name: str) -> Callable[[T], T]: ...

    @overload
    def register(self, name: str, entry: T) -> T: ...

    def register(self, name: str, entry: T | None = None) -> T | Callable[[T], T]:
        """Add ``entry`` under ``name``; without ``entry``, a decorator doing so.

        A name can be registered once: a second registration is a :class:`ModelError`."""
        if not isinstance(name, str) or not name or name != name.strip():
            raise ModelError(f"{self.kind} name must be a non-empty string without surrounding "
                             f"spaces (got {name!r})")

        def add(obj: T) -> T:
            if name in self._entries:
                raise ModelError(f"{self.kind} {name!r} is already registered "
                                 f"({self._entries[name]!r}); choose another name")
            self._entries[name] = obj
            return obj

        return add if entry is None else add(entry)

    def unregister(self, name: str) -> T:
        """Remove ``name`` and return its entry (a plug-in withdrawn, a test cleaning up)."""
        entry = self.get(name)
        del self._entries[name]
        return entry

    def get(self, name: str) -> T:
        """The entry of ``name``; an unknown name is a :class:`ModelError` listing the known ones."""
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            raise ModelError(self.unknown(name)) from None

    def unknown(self, name: object) -> str:
        """The one-line message for an unknown ``name``: ``unknown <kind> 'x' (known: a, b)``."""
        return f"unknown {self.kind} {name!r} (known: {', '.join(self._entries) or 'none'})"

    def names(self) -> tuple[str, ...]:
        """Registered names in registration order."""
        return tuple(self._entries)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(self._entries))

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(self._entries)})"
