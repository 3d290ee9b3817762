"""SHA-256 of input files, as the output headers and reports name them (docs/guarantees.md "Output
safety")."""

from __future__ import annotations

import hashlib
import os

from accugrid.infra.inputfile import read_input_bytes

__all__ = ["file_sha256", "sha256_hex"]


def sha256_hex(data: bytes) -> str:
    """SHA-256 (64 hex digits) of bytes already read."""
    return hashlib.sha256(data).hexdigest()


def file_sha256(path: str | os.PathLike[str]) -> str:
    """SHA-256 (hex) of a file's bytes, read through the guarded input reader."""
    return sha256_hex(read_input_bytes(path))
