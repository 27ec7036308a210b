"""Detection on a Dask cluster: videos decoded in segments on many machines, events identical.

The unit of work is a (video, segment) (:mod:`flashsync.segments`): segments start at key
frames, so each decodes on its own to the same row profiles as the whole video does. Decoding
is nearly all of detection's cost, and the segments of all videos decode in parallel on the
workers. What carries from frame to frame (the flicker model, the baselines, the recurrence
filter, the event numbers: :class:`~flashsync.detect.VideoDetection`) is then handed from
each segment to the next of its video, one small task per segment, so the events are those of
the plain run by construction, not by a warm-up that only approximates its state. Workers read
the videos by path: every worker must see them under the same path (a shared filesystem).

Workers started with ``dask worker --preload flashsync.cluster`` import the detector and
load its compiled kernels when they start (:func:`dask_setup`); otherwise the first step of
a job's chain does it, on the job's time.

``scheduler`` is ``tcp://HOST:PORT`` of a running scheduler (``dask scheduler``, with
``dask worker tcp://HOST:PORT`` on each machine) or ``local:N`` for a
:class:`distributed.LocalCluster` of N worker processes on this machine. Dask is an optional
extra (``pip install 'flashsync[cluster]'``), imported here only.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from flashsync.detect import CameraDetection, DetectorSettings, VideoDetection
from flashsync.errors import FlashsyncError, InputError
from flashsync.profiles import VideoInfo
from flashsync.segments import SEGMENT_MS, check_complete, plan_segments, read_segment

#: How long to wait for a scheduler to answer, s.
CONNECT_TIMEOUT_S = 10
#: Most worker processes local:N starts per CPU of this machine: more only fight for the CPUs
#: and memory (local:100000 would start 100000 Python processes).
LOCAL_WORKERS_PER_CPU = 4
#: Dask priority of a video's chain of detection steps over the decoding of segments (0): a
#: segment's step runs as soon as the segment and the step before are done, overlapping the
#: decoding of the later segments, instead of queueing behind every segment's decoding and
#: running one after the other at the end.
CHAIN_PRIORITY = 1


def check_scheduler(scheduler: str) -> None:
    """Raise an :class:`~flashsync.errors.InputError` (parameter ``scheduler``) unless the
    address is ``tcp://HOST:PORT`` or ``local:N`` (N >= 1); imports nothing."""
    local = re.fullmatch(r"local:(\d+)", scheduler)
    tcp = re.fullmatch(r"tcp://[^\s:/]+:(\d+)", scheduler)
    if not (tcp or (local and int(local.group(1)) >= 1)):
        raise InputError(
            f"{scheduler}: expected tcp://HOST:PORT of a running Dask scheduler or local:N for N worker "
            "processes on this machine",
            parameter="scheduler",
        )
    cpus = os.cpu_count() or 1
    if local and int(local.group(1)) > LOCAL_WORKERS_PER_CPU * cpus:
        raise InputError(
            f"{scheduler}: {local.group(1)} worker processes on this machine of {cpus} CPUs; give at most "
            f"local:{LOCAL_WORKERS_PER_CPU * cpus} (each worker is a Python process decoding video)",
            parameter="scheduler",
        )
    if tcp and not 1 <= int(tcp.group(1)) <= 65535:
        raise InputError(
            f"{scheduler}: port {tcp.group(1)} is not a TCP port (1-65535); give the port the scheduler listens on "
            "(dask scheduler's default is 8786)",
            parameter="scheduler",
        )


@contextmanager
def connect(scheduler: str) -> Iterator:
    """A :class:`distributed.Client` of the scheduler (see the module's text); a cluster it
    started is shut down on leaving."""
    check_scheduler(scheduler)
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError(
            f"{scheduler}: running on a Dask cluster needs the cluster extra: pip install 'flashsync[cluster]'",
            parameter="scheduler",
        ) from None
    if scheduler.startswith("local:"):
        n_workers = int(scheduler.partition(":")[2])
        # its scheduler serves HTTP whatever the dashboard setting (distributed 2026.8), on 8787
        # unless told otherwise, and warns on stderr where that port is taken: a free port instead
        with (
            LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster,
            Client(cluster) as client,
        ):
            yield client
        return
    try:
        _handshake(scheduler)
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as error:
        why = str(error) or f"no Dask handshake within {CONNECT_TIMEOUT_S + 1} s: something else listens there"
        raise InputError(
            f"{scheduler}: no Dask scheduler answers there ({why}); start one with 'dask scheduler' "
            "and workers with 'dask worker ADDRESS', or give local:N",
            parameter="scheduler",
        ) from None
    with client:
        yield client


def _handshake(scheduler: str) -> None:
    """Connect to ``scheduler`` and exchange Dask's handshake within ``CONNECT_TIMEOUT_S + 1`` s,
    else an OSError or TimeoutError: distributed's own connect waits for the handshake without a
    limit, so a server of another kind on the port (an HTTP server) would hang the Client."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    from distributed.comm import connect as open_comm

    async def exchange():
        comm = await asyncio.wait_for(open_comm(scheduler, timeout=CONNECT_TIMEOUT_S), CONNECT_TIMEOUT_S + 1)
        await comm.close()

    with ThreadPoolExecutor(1) as pool:  # an event loop of its own, wherever this is called from
        pool.submit(asyncio.run, exchange()).result()


def detect_on_cluster(
    scheduler: str,
    paths: Sequence[Path],
    flipped: Sequence[bool | None],
    settings: DetectorSettings | None = None,
    progress: Callable[[str, int], Callable[[int], None] | None] | None = None,
    segment_ms: float = SEGMENT_MS,
) -> list[CameraDetection]:
    """:func:`~flashsync.detect.detect_video` of each video, on the cluster ``scheduler``.

    Parameters
    ----------
    scheduler : ``tcp://HOST:PORT`` or ``local:N``.
    paths : videos, each readable by every worker under this path.
    flipped : per video, as ``detect_video``'s ``flipped``.
    settings, progress : as for ``detect_video``; progress counts the frames of each segment
        once it is decoded.
    segment_ms : segments of at least this long (ms), each starting at a key frame.

    Returns
    -------
    list of CameraDetection, one per path, equal to what ``detect_video`` gives.
    """
    with connect(scheduler) as client:
        from distributed import as_completed

        futures = []
        try:
            plans = client.map(plan_segments, list(paths), segment_ms=segment_ms, pure=False)
            futures += plans
            results, counts = [], []
            for (info, segments), direction in zip(client.gather(plans), flipped):
                update = progress(info.camera, info.n_frames_hint) if progress else None
                parts = client.map(read_segment, segments, pure=False)
                state = (info, direction, settings)  # the first step starts the pass where its segment decoded
                futures += parts
                for index, part in enumerate(parts):
                    state = client.submit(
                        _detect_segment, state, part, index == len(parts) - 1, pure=False, priority=CHAIN_PRIORITY
                    )
                    futures.append(state)
                    if update is not None:
                        counts.append((client.submit(len, part, pure=False), update))
                results.append(state)
            futures += [count for count, _ in counts]
            updates = dict(counts)
            for count in as_completed(list(updates)):
                updates[count](count.result())
            return client.gather(results)
        except BaseException:  # an error or an interrupt: nothing more runs for this call
            client.cancel(futures)
            raise


def _detect_segment(state: VideoDetection | tuple, frames: list, last: bool) -> VideoDetection | CameraDetection:
    """Push one segment's frames (:func:`~flashsync.segments.read_segment`) in order; after the
    last segment, check the video is complete and return its detection. The state is the
    previous task's result and nothing else uses it, so it is updated in place; the first
    segment's is ``VideoDetection``'s arguments."""
    if not isinstance(state, VideoDetection):
        state = VideoDetection(*state)
    for frame in frames:
        state.push(*frame)
    if not last:
        return state
    check_complete(state.info.path, state.n_frames, [frame[0] for frame in frames[-2:]])
    return state.finish()


def dask_setup(worker=None) -> float:
    """Warm a worker up (``dask worker --preload flashsync.cluster`` calls it at start): one
    small synthetic video's detection, flash included, loads or compiles every kernel a
    segment's step uses. Returns the time it took, s."""
    start = time.perf_counter()
    rng = np.random.default_rng(0)
    state = VideoDetection(VideoInfo(Path("warm-up.mkv"), 64, 48, 60), None)
    for frame in range(60):
        profile = 0.5 + 0.01 * rng.standard_normal((48, 8)).astype(np.float32)
        if frame == 30:
            profile[20:] *= 1.5  # a flash band from row 20 down
        state.push(frame * 40.0, profile, frame % 20 == 0)
    try:
        state.finish()
    except FlashsyncError:  # too little to detect anything is fine: the kernels ran
        pass
    return time.perf_counter() - start
