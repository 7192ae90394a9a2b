"""ALFA dataset folders (mavros topics as CSV, :mod:`uasnav.io.alfa`): navigation data and the
IMU, read whole (one file per topic, each opened once)."""

from __future__ import annotations

from typing import Any, ClassVar

from uasnav.io.flight import Flight
from uasnav.io.formats.base import LogFormat
from uasnav.io.views import Identity


class AlfaFormat(LogFormat):
    """A CMU ALFA ROS-topic CSV folder."""

    name = "alfa-ros-csv"
    SOURCES: ClassVar[dict[str, tuple[str, ...]]] = {"nav": (), "imus": (), "imu": (), "identity": ()}

    def build_nav(self) -> Flight:
        cached = self.options.get("_nav")
        if cached is None:
            from uasnav.io.alfa import read_alfa_folder

            cached = self.options["_nav"] = read_alfa_folder(self.path)
        return cached  # type: ignore[no-any-return]

    def build_imus(self) -> dict[str, Any]:
        return dict(self.build_nav().imus)

    def build_imu(self) -> Any:
        return self.build_nav().imu

    def build_identity(self) -> Identity:
        return Identity(autopilot="PX4", vehicle_type="fixed-wing", clock="file")


__all__ = ["AlfaFormat"]
