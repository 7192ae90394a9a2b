"""Derive ``python/uasnav/geo/data/egm96_15.npy.xz`` from PROJ's ``egm96_15.gtx``.

The grid is NGA's EGM96 geoid on a 15′ lattice (721 rows, 90° S → 90° N; 1440 columns,
180° W → 179.75° E), as distributed by PROJ (Debian package ``proj-data``). It is stored as
int16 centimetres (rounding ≤ 5 mm), differenced along longitude then latitude (exact in
integers; the smooth geoid makes the differences small) and compressed with xz: about 0.5 MB.
:mod:`uasnav.geo.geoid` undoes the differences with two cumulative sums.

Usage: ``python scripts/make_geoid_grid.py [/usr/share/proj/egm96_15.gtx]``
"""

from __future__ import annotations

import io
import lzma
import struct
import sys
from pathlib import Path

import numpy as np

OUT = Path(__file__).resolve().parents[1] / "python" / "uasnav" / "geo" / "data" / "egm96_15.npy.xz"


def main(src: str = "/usr/share/proj/egm96_15.gtx") -> None:
    raw = Path(src).read_bytes()
    # GTX: big-endian header (lower-left lat, lon, Δlat, Δlon in degrees; rows, columns), then
    # float32 metres row by row from the south.
    lat0, lon0, dlat, dlon, rows, cols = struct.unpack(">4d2i", raw[:40])
    if (lat0, lon0, dlat, dlon, rows, cols) != (-90.0, -180.0, 0.25, 0.25, 721, 1440):
        raise SystemExit(
            f"{src}: not the global EGM96 15′ grid ({lat0}, {lon0}, {dlat}, {dlon}, {rows}, {cols})"
        )
    grid = np.frombuffer(raw[40:], dtype=">f4").reshape(rows, cols)
    cm = np.round(grid.astype(np.float64) * 100.0).astype(np.int32)
    packed = np.diff(np.diff(cm, axis=1, prepend=0), axis=0, prepend=0)
    assert np.abs(packed).max() < 2**15
    buf = io.BytesIO()
    np.save(buf, packed.astype("<i2"), allow_pickle=False)
    OUT.write_bytes(lzma.compress(buf.getvalue(), preset=9))
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes)")


if __name__ == "__main__":
    main(*sys.argv[1:2])
