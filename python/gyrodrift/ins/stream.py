"""The streaming engine: N navigators over one read of an IMU log, split at whole hours.

`run_navigators` reads a `gyrodrift.logs.ImuLog` (a file, in-memory arrays or a scenario simulated on the fly)
once, from sample ``start`` to ``start + n_samples``, and hands every chunk to each navigator in turn (or on
threads: the core releases the GIL); the next chunks are read and checked on a thread meanwhile
(`prefetched`), unless ``threads=1`` keeps the whole read on the calling thread (a process that must use one
core, such as a campaign worker). Chunks are split at whole hours counted from ``start``, so the state at
every hour is exact (not decimated). Every ``decimation``-th state (counted from ``start``, as the core counts
its own samples) is copied into arrays allocated once for the whole run, so memory does not grow with the log
beyond those outputs and nothing keeps a chunk of the log alive.

The navigators are built by the caller (`gyrodrift.ins.navigate`, `gyrodrift.procedure.passes`): anything with
``process(dtheta_rad, dv_m_s, decimation) -> dict`` and ``state() -> dict`` (`gyrodrift._core.Navigator`; with
``reference``, ``process(dtheta_rad, dv_m_s, decimation, reference_height_m)``: the damped vertical channel's
reference height per sample; with an ``axial_bias`` for the navigator, ``process(dtheta_rad, dv_m_s, decimation,
reference_height_m or None, axial_bias_rad_s)``: its z gyro bias per sample, `gyrodrift.ins.compensation`).
"""

from __future__ import annotations

import contextlib
import os
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from gyrodrift.logs import DEFAULT_CHUNK_SAMPLES, ImuLog, LogChunk
from gyrodrift.progress import progress
from gyrodrift.units import HOUR

__all__ = ["Track", "run_navigators", "prefetched", "STATE_KEYS"]

T = TypeVar("T")

STATE_KEYS = ("t_s", "lat_rad", "lon_rad", "height_m", "vel_enu_m_s", "pitch_rad", "roll_rad", "yaw_rad")
"""What the core navigator returns per kept sample (``vel_enu_m_s`` has 3 columns)."""


@dataclass
class Track:
    """What one navigator left along the read.

    Attributes
    ----------
    kept : dict of str to ndarray
        The kept states (every ``decimation`` samples from ``start``), for the keys asked: (m,) arrays, (m, 3)
        for ``vel_enu_m_s``.
    hourly : list of (int, dict)
        (k, state) after whole navigation hour k = 1, 2, ... (exact).
    final : dict
        The state after the last navigated sample.
    """

    kept: dict[str, np.ndarray]
    hourly: list[tuple[int, dict[str, Any]]] = field(default_factory=list)
    final: dict[str, Any] = field(default_factory=dict)


def prefetched(items: Iterator[T], depth: int = 2) -> Iterator[T]:
    """Iterate `items` with up to `depth` items produced ahead on a thread.

    The next chunks of a log are read, decoded and checked while the core navigates the current one (pyarrow,
    numpy and the core release the GIL), so a navigation costs about the larger of reading and navigating
    instead of their sum; memory grows by `depth` chunks. An exception of the producer is raised here, in
    order; leaving the loop early stops the producer and closes `items`.
    """
    q: queue.Queue = queue.Queue(maxsize=depth)
    stop = threading.Event()
    end = object()

    def put(entry) -> bool:
        while not stop.is_set():
            try:
                q.put(entry, timeout=0.05)
                return True
            except queue.Full:
                continue
        return False

    def produce() -> None:
        try:
            for item in items:
                if not put((item, None)):
                    return
            put((end, None))
        except BaseException as exc:  # handed to the consumer, raised there
            put((end, exc))

    worker = threading.Thread(target=produce, name="gyrodrift-prefetch", daemon=True)
    worker.start()
    try:
        while True:
            item, exc = q.get()
            if item is end:
                if exc is not None:
                    raise exc
                return
            yield item
    finally:
        stop.set()
        worker.join()
        close = getattr(items, "close", None)
        if close is not None:
            close()


def run_navigators(
    log: ImuLog,
    navigators: Sequence[Any],
    *,
    n_samples: int,
    start: int = 0,
    decimation: int = 1,
    keys: Sequence[str] = STATE_KEYS,
    observe: Callable[[LogChunk, int], None] | None = None,
    reference: Callable[[LogChunk], np.ndarray] | None = None,
    axial_bias: Sequence[Callable[[LogChunk], np.ndarray] | None] | None = None,
    threads: int | None = None,
    chunk_samples: int = DEFAULT_CHUNK_SAMPLES,
    quiet: bool = True,
    desc: str = "navigate",
) -> list[Track]:
    """Navigate samples ``start .. start + n_samples - 1`` of `log` with every navigator, in one read.

    Parameters
    ----------
    log : ImuLog
        The source; it is read (and validated) from its first sample, the samples before `start` are skipped.
    navigators : sequence
        Core navigators positioned at sample `start` (built and biased by the caller).
    n_samples : int
        Samples to navigate (>= 1; the log must hold ``start + n_samples``).
    decimation : int
        Keep the state after every `decimation`-th navigated sample.
    keys : sequence of str
        Which `STATE_KEYS` to keep.
    observe : callable, optional
        ``observe(chunk, done)`` for every navigated piece of the log (`chunk` a `LogChunk` of views, `done` the
        samples navigated before it); must not keep references to the views.
    reference : callable, optional
        ``reference(chunk)``: the reference height [m] at the end of each sample of a piece, handed to every
        navigator's ``process`` (the damped vertical channel's reference: a log column, a route's height).
    axial_bias : sequence, optional
        One per navigator: ``axial_bias(chunk)``, the z gyro bias [rad/s] of each sample of a piece for that
        navigator (a drift law on the temperature, `gyrodrift.ins.compensation.AxialBias`: called once per piece,
        in order), or None for a navigator keeping its own constant bias.
    threads : int, optional
        Threads running the navigators of one piece side by side (default: one per navigator, at most the
        number of CPUs, and the log read ahead on one more thread). 1 = everything on the calling thread:
        navigators in turn and no read-ahead. Results do not depend on it.
    chunk_samples, quiet, desc
        Read size, progress switch and label.

    Returns
    -------
    list of Track
        One per navigator, in order.
    """
    if axial_bias is not None and len(axial_bias) != len(navigators):
        raise ValueError(f"run_navigators: {len(axial_bias)} axial biases for {len(navigators)} navigators")
    per_hour = max(1, log.samples_for(HOUR))
    dec = int(decimation)
    m = n_samples // dec
    tracks = [Track(kept={k: np.empty((m, 3) if k == "vel_enu_m_s" else m) for k in keys}) for _ in navigators]
    stop = start + n_samples
    done = 0
    pos = 0
    n_threads = min(len(navigators), os.cpu_count() or 1) if threads is None else max(1, min(threads, len(navigators)))
    pool = ThreadPoolExecutor(max_workers=n_threads) if n_threads > 1 else None
    with log.core_errors(start), progress(n_samples, desc, quiet) as bar, pool or contextlib.nullcontext():
        chunks = log.chunks(chunk_samples, stop=stop)
        for chunk in chunks if threads == 1 else prefetched(chunks):
            if chunk.first_index + len(chunk) <= start:
                continue
            if chunk.first_index < start:
                chunk = chunk.slice(start - chunk.first_index, len(chunk))
            a = 0
            while a < len(chunk):
                b = min(len(chunk), a + per_hour - (done % per_hour))  # end at the next whole hour
                piece = chunk.slice(a, b)
                if observe is not None:
                    observe(piece, done)
                args = _process_args(piece, dec, reference, axial_bias, len(navigators))
                if pool is None:
                    outs = [nav.process(*a) for nav, a in zip(navigators, args, strict=True)]
                else:
                    outs = list(pool.map(lambda nav, a: nav.process(*a), navigators, args))
                k = (done + b - a) // dec - done // dec  # kept states in this piece
                for track, out in zip(tracks, outs, strict=True):
                    for key in keys:
                        track.kept[key][pos : pos + k] = np.asarray(out[key], dtype=float).reshape(
                            track.kept[key][pos : pos + k].shape
                        )
                pos += k
                done += b - a
                if done % per_hour == 0:
                    for track, nav in zip(tracks, navigators, strict=True):
                        track.hourly.append((done // per_hour, nav.state()))
                a = b
            bar.update(len(chunk))
            del chunk
    for track, nav in zip(tracks, navigators, strict=True):
        track.final = nav.state()
    return tracks


def _process_args(
    piece: LogChunk,
    dec: int,
    reference: Callable[[LogChunk], np.ndarray] | None,
    axial_bias: Sequence[Callable[[LogChunk], np.ndarray] | None] | None,
    n_navigators: int,
) -> list[tuple[Any, ...]]:
    """Each navigator's ``process`` arguments for `piece` (the per-sample inputs computed once per piece, in
    order: an `AxialBias` carries its temperature-rate state from piece to piece)."""
    args: tuple[Any, ...] = (piece.dtheta_rad, piece.dv_m_s, dec)
    heights = None if reference is None else reference(piece)
    if heights is not None:
        args += (heights,)
    if axial_bias is None:
        return [args] * n_navigators
    out = []
    for bias in axial_bias:
        if bias is None:
            out.append(args)
        else:
            out.append((piece.dtheta_rad, piece.dv_m_s, dec, heights, bias(piece)))
    return out
