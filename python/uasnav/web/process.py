"""Run ``uasnav serve`` as its own process (tests, benchmarks, scripts).

:func:`running_server` starts the real command on a free loopback port, waits until it answers
and stops it on exit, so that what is tested and measured is what an operator starts.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from uasnav.errors import UasnavError


def free_port(host: str = "127.0.0.1") -> int:
    """A TCP port free on ``host`` now (the kernel's choice)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((host, 0))
        return int(s.getsockname()[1])


def uasnav_command() -> list[str]:
    """The installed ``uasnav`` script beside this interpreter (or on PATH)."""
    here = Path(sys.executable).parent / "uasnav"
    found = str(here) if here.exists() else shutil.which("uasnav")
    if found is None:
        raise UasnavError("the uasnav command is not installed (run make setup)")
    return [found]


@dataclass
class Server:
    """A running ``uasnav serve``: its base URL, process and captured stderr file."""

    url: str
    port: int
    process: subprocess.Popen[bytes]
    log_path: Path

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")


@contextlib.contextmanager
def running_server(
    *args: str,
    host: str = "127.0.0.1",
    port: int | None = None,
    timeout_s: float = 60.0,
    log_dir: Path | None = None,
) -> Iterator[Server]:
    """Start ``uasnav serve --host HOST --port PORT ARGS…`` and yield once it answers.

    Raises
    ------
    UasnavError
        The process exited or did not answer ``/api/options`` within ``timeout_s``.
    """
    import tempfile

    port = port or free_port(host if host not in ("0.0.0.0", "::") else "127.0.0.1")
    tmp = tempfile.TemporaryDirectory(prefix="uasnav-serve-") if log_dir is None else None
    log_path = Path(tmp.name if tmp else str(log_dir)) / f"serve-{port}.log"
    cmd = [*uasnav_command(), "serve", "--host", host, "--port", str(port), *args]
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True)
    probe_host = "127.0.0.1" if host in ("0.0.0.0", "::", "localhost") else host
    url = f"http://{probe_host}:{port}"
    server = Server(url, port, proc, log_path)
    try:
        deadline = time.monotonic() + timeout_s
        while True:
            if proc.poll() is not None:
                raise UasnavError(f"uasnav serve exited with {proc.returncode}: {server.log()[-2000:]}")
            try:
                with urllib.request.urlopen(url + "/api/options", timeout=2) as r:
                    if r.status == 200:
                        break
            except OSError:
                pass
            if time.monotonic() > deadline:
                raise UasnavError(f"uasnav serve did not answer within {timeout_s} s: {server.log()[-2000:]}")
            time.sleep(0.1)
        yield server
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)  # uvicorn's graceful shutdown
            try:
                proc.wait(timeout=10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if tmp is not None:
            tmp.cleanup()


__all__ = ["Server", "free_port", "running_server", "uasnav_command"]
