"""Binned means of calibration data: the one place that averages samples into bins.

Two ways to form the bins, one way to average them:

* :func:`bin_by_temperature` — bins of ``width_c`` °C over the temperature span (the data
  derivative of the thesis' derivative networks, §4.2.6.1);
* :func:`bin_by_time` — consecutive blocks of ``seconds`` s (``uasnav calibrate --average``:
  a static log's gyro output averaged before fitting).

Both return the mean temperature and the mean values of every non-empty bin, in bin order.

>>> import numpy as np
>>> temp = np.array([20.0, 20.4, 21.2, 21.6, 23.1])
>>> values = np.array([[1.0], [3.0], [5.0], [7.0], [9.0]])
>>> tm, vm = bin_by_temperature(temp, values, 1.0)
>>> tm.round(2).tolist(), vm.ravel().tolist()
([20.2, 21.4, 23.1], [2.0, 6.0, 9.0])
>>> tm, vm = bin_by_time(np.array([0.0, 0.5, 1.0, 1.5, 2.0]), temp, values, 1.0)
>>> vm.ravel().tolist()
[2.0, 6.0, 9.0]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from uasnav.errors import InputError
from uasnav.limits import check_count
from uasnav.thermal._common import FloatArray, check_temp


def bin_means(
    index: NDArray[np.integer], temp: FloatArray, values: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Mean temperature and mean values of the samples sharing a bin index.

    Parameters
    ----------
    index : ndarray of int, shape (n,)
        Bin of each sample (≥ 0).
    temp : ndarray, shape (n,)
        Temperatures (°C).
    values : ndarray, shape (n, k)
        Values to average (any unit, e.g. gyro output rad/s).

    Returns
    -------
    temp_mean : ndarray, shape (m,)
        Mean temperature of each non-empty bin (°C), in bin order.
    values_mean : ndarray, shape (m, k)
        Mean values of each non-empty bin (unit of ``values``).
    """
    # Bin indices renumbered 0…m−1 over the non-empty bins (same order, same sums): memory grows
    # with the samples, never with the largest index (1e15 from a tiny block length).
    _, index = np.unique(index, return_inverse=True)
    index = index.ravel()
    counts = np.bincount(index)
    ok = counts > 0
    tm = np.bincount(index, temp, minlength=counts.size)[ok] / counts[ok]
    vm = (
        np.stack([np.bincount(index, col, minlength=counts.size)[ok] for col in values.T], 1)
        / counts[ok][:, None]
    )
    return tm, vm


def bin_by_temperature(temp: ArrayLike, values: ArrayLike, width_c: float) -> tuple[FloatArray, FloatArray]:
    """Means over temperature bins of ``width_c`` °C.

    The bins start at the lowest temperature: ``[T_min + i·width_c, T_min + (i+1)·width_c)``;
    the highest temperature falls in the last bin.

    Parameters
    ----------
    temp : array_like, shape (n,)
        Temperatures (°C).
    values : array_like, shape (n, k)
        Values to average (e.g. gyro bias, rad/s).
    width_c : float
        Bin width (°C), > 0.

    Returns
    -------
    temp_mean : ndarray, shape (m,)
        Mean temperature of each non-empty bin (°C), increasing.
    values_mean : ndarray, shape (m, k)
        Mean values per bin.
    """
    if not (np.isfinite(width_c) and width_c > 0):
        raise InputError(f"width_c: expected a bin width > 0 °C, got {width_c}")
    t = check_temp(temp)
    v = np.asarray(values, dtype=np.float64)
    # The edges are allocated: bound their number before (a width of 1e-12 °C would ask for 10¹⁴).
    check_count(np.ptp(t) / width_c + 2, 8, f"temperature bins of {width_c:g} °C", option="the bin width")
    edges = np.arange(t.min(), t.max() + width_c, width_c)
    idx = np.clip(np.digitize(t, edges) - 1, 0, edges.size - 2)
    return bin_means(idx, t, v)


def bin_by_time(
    t: ArrayLike, temp: ArrayLike, values: ArrayLike, seconds: float
) -> tuple[FloatArray, FloatArray]:
    """Means over consecutive time blocks of ``seconds`` s: ``[t₀ + i·seconds, t₀ + (i+1)·seconds)``.

    ``seconds ≤ 0`` means no averaging: ``temp`` and ``values`` are returned as they are.

    Parameters
    ----------
    t : array_like, shape (n,)
        Sample times (s), increasing.
    temp : array_like, shape (n,)
        Temperatures (°C).
    values : array_like, shape (n, k)
        Values to average (e.g. gyro output, rad/s).
    seconds : float
        Block length (s).

    Returns
    -------
    temp_mean : ndarray, shape (m,)
        Mean temperature of each non-empty block (°C).
    values_mean : ndarray, shape (m, k)
        Mean values per block.
    """
    tt = np.asarray(t, dtype=np.float64)
    te = np.asarray(temp, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    if not np.isfinite(seconds):
        raise InputError(f"seconds: expected a finite block length (s), got {seconds}")
    if seconds <= 0 or tt.size == 0:
        return te, v
    q = np.floor((tt - tt[0]) / seconds)
    if not np.isfinite(q).all() or q.max() >= 2.0**62:
        raise InputError(f"seconds: block length {seconds:g} s is too short for a log of {np.ptp(tt):g} s")
    return bin_means(q.astype(np.int64), te, v)


class TimeBlockMeans:
    """:func:`bin_by_time` over a log given piece by piece (a file read in chunks): the same
    blocks and means, up to the rounding of a block's sum split across two pieces, in memory
    that grows with the number of blocks only.

    >>> acc = TimeBlockMeans(1.0)
    >>> acc.add(np.array([0.0, 0.5, 1.0]), np.array([20.0, 20.4, 21.2]), np.array([[1.0], [3.0], [5.0]]))
    >>> acc.add(np.array([1.5, 2.0]), np.array([21.6, 23.1]), np.array([[7.0], [9.0]]))
    >>> acc.result()[1].ravel().tolist()
    [2.0, 6.0, 9.0]
    """

    def __init__(self, seconds: float) -> None:
        if not (np.isfinite(seconds) and seconds > 0):
            raise InputError(f"seconds: expected a block length > 0 s, got {seconds}")
        self.seconds = float(seconds)
        self._t0: float | None = None
        self._t_last = 0.0
        self._too_fine = False
        self._q: list[NDArray[np.int64]] = []
        self._n: list[FloatArray] = []
        self._temp: list[FloatArray] = []
        self._values: list[FloatArray] = []

    def add(self, t: FloatArray, temp: FloatArray, values: FloatArray) -> None:
        """Add samples: ``t`` (m,) s increasing and after those added before, ``temp`` (m,) °C,
        ``values`` (m, k)."""
        if t.size == 0:
            return
        if self._t0 is None:
            self._t0 = float(t[0])
        self._t_last = float(t[-1])
        if self._too_fine:
            return
        q = np.floor((t - self._t0) / self.seconds)
        if not np.isfinite(q).all() or q.max() >= 2.0**62:
            self._too_fine = True  # reported by result(), with the log's whole span
            self._q, self._n, self._temp, self._values = [], [], [], []
            return
        qi = q.astype(np.int64)
        # q never decreases (t increases): a block is a run of equal q
        starts = np.flatnonzero(np.diff(qi, prepend=qi[0] - 1))
        idx = np.repeat(np.arange(starts.size), np.diff(np.append(starts, qi.size)))
        n = np.bincount(idx).astype(np.float64)
        tsum = np.bincount(idx, temp)
        vsum = np.stack([np.bincount(idx, col) for col in np.asarray(values).T], 1)
        self._q.append(qi[starts])
        self._n.append(n)
        self._temp.append(tsum)
        self._values.append(vsum)

    def result(self) -> tuple[FloatArray, FloatArray]:
        """(mean temperature (m,) °C, mean values (m, k)) per non-empty block, in time order."""
        if self._too_fine:
            span = self._t_last - (self._t0 or 0.0)
            raise InputError(f"seconds: block length {self.seconds:g} s is too short for a log of {span:g} s")
        if not self._q:
            return np.empty(0), np.empty((0, 0))
        q = np.concatenate(self._q)
        # a block split across two pieces: its sums are added
        _, inv = np.unique(q, return_inverse=True)
        inv = inv.ravel()
        n = np.bincount(inv, np.concatenate(self._n))
        tm = np.bincount(inv, np.concatenate(self._temp)) / n
        v = np.concatenate(self._values)
        vm = np.stack([np.bincount(inv, col) for col in v.T], 1) / n[:, None]
        return tm, vm


__all__ = ["TimeBlockMeans", "bin_by_temperature", "bin_by_time", "bin_means"]
