"""A minimal ULog (version 1) writer for tests, following the format specification
(https://docs.px4.io/main/en/dev_log/ulog_file_format.html: file header, ``F`` formats, ``A``
subscriptions, ``D`` data). The shared ULogs lack some topics the readers must handle (mission
items; a log without GNSS), so tests write such logs here and read them back through pyulog.

Array fields are written as scalar fields named ``name[i]``: pyulog flattens arrays to exactly
those keys, so readers see the same data as from a real ``float[3] name`` field.
"""

from __future__ import annotations

import struct
from pathlib import Path

_TYPES = {
    "uint64_t": "Q", "int32_t": "i", "uint32_t": "I", "uint16_t": "H", "uint8_t": "B", "bool": "?",
    "float": "f", "double": "d",
}  # fmt: skip


def _msg(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_ulog(path: Path, topics: dict[str, tuple[tuple[tuple[str, str], ...], list[dict]]]) -> None:
    """A minimal ULog (version 1): header, one info message, then for each topic its format,
    one subscription (multi id 0) and its records as data messages (fields packed in order,
    little-endian, no padding — as the format defines)."""
    out = bytearray(b"ULog\x01\x12\x35\x01" + struct.pack("<Q", 0))
    key = b"char[4] ver_sw"
    out += _msg(b"I", bytes([len(key)]) + key + b"test")
    for name, (fields, _) in topics.items():
        fmt = f"{name}:" + "".join(f"{t} {f};" for t, f in fields)
        out += _msg(b"F", fmt.encode())
    for msg_id, name in enumerate(topics):
        out += _msg(b"A", struct.pack("<BH", 0, msg_id) + name.encode())
    for msg_id, (_, (fields, rows)) in enumerate(topics.items()):
        pack = "<" + "".join(_TYPES[t] for t, _ in fields)
        for r in rows:
            out += _msg(b"D", struct.pack("<H", msg_id) + struct.pack(pack, *(r[f] for _, f in fields)))
    path.write_bytes(bytes(out))
