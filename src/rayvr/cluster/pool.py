"""`Cluster`: Ray actors that each own one GPU (a RenderWorker), and the loop that runs a job's
shares on them.

    with rayvr.cluster.Cluster(workers=2) as cluster:          # a local Ray, or address="host:6379"
        ref = rayvr.cluster.converge_reference(scene, views, frames=1024, spp=4, cluster=cluster)

- Each worker asks Ray for one GPU where the cluster has as many as workers, a share of them
  where it has fewer (several workers on one GPU), none on a CPU-only cluster (llvmpipe).
- Scenes go into Ray's object store once per Cluster (`scene_ref`); each worker fetches and
  loads one the first time a share needs it.
- Faults: a worker that dies (killed, its process exited, its GPU lost: a GpuError) has its share
  re-run on another worker, and is replaced by a new one. A share that fails on `max_attempts`
  workers, or a job whose workers all died, ends in ClusterError. Any other RayvrError from a
  worker (bad input) ends the job with that error.
- Ctrl-C (KeyboardInterrupt) kills the workers that are busy and re-raises; nothing of the job is
  returned, so the caller writes nothing. Killed workers are replaced at the next job.
- Progress: workers count what they finish in a ProgressCounter actor; the driver shows one bar.
"""
from __future__ import annotations

import collections
import dataclasses
import itertools
import time

from ..errors import ClusterError, GpuError, RayvrError
from .payload import ScenePayload
from .progress import JobBar, ProgressCounter
from .ray_support import require_ray
from .shares import Share
from .worker import RenderWorker

POLL_S = 0.25            # the driver's loop: wait for a result at most this long, then poll progress
START_TIMEOUT_S = 300.0  # workers must be up (context, device) within this
RELEASE_WAIT_S = 30.0    # Ray returns a killed worker's GPU a moment later: wait this long for it


def worker_shares(ray, workers: int | None, gpus_per_worker: float | None,
                  wait_s: float = RELEASE_WAIT_S) -> tuple[int, float, dict]:
    """How many workers to start, the Ray GPUs each asks for, and the free resources: a GPU per
    worker where the cluster has as many, else a share of them, none without GPUs (see Cluster).
    GPUs that workers closed just before still hold (another Cluster of this process, a job's
    previous Cluster) are waited for up to `wait_s`, since Ray frees them asynchronously."""
    total = float(ray.cluster_resources().get("GPU", 0.0))
    count = int(workers) if workers else max(1, int(total))
    if count < 1:
        raise ClusterError(f"--workers {workers}: need at least 1 worker")
    want = min(total, count) if gpus_per_worker is None else float(gpus_per_worker) * count
    deadline = time.monotonic() + wait_s
    free = ray.available_resources()
    while float(free.get("GPU", 0.0)) + 1e-9 < want and want <= total + 1e-9 and time.monotonic() < deadline:
        time.sleep(0.25)
        free = ray.available_resources()
    gpus = float(free.get("GPU", 0.0))
    if gpus_per_worker is None:
        if total and not gpus:
            raise ClusterError(f"the cluster's {total:g} GPUs are all in use; free one or wait")
        gpus_per_worker = 1.0 if gpus >= count else gpus / count
    if gpus_per_worker * count > gpus + 1e-9:
        raise ClusterError(f"{count} workers x {gpus_per_worker:g} GPU need {gpus_per_worker * count:g} GPUs; "
                           f"the cluster has {gpus:g} free: ask for fewer workers or a share of a GPU each")
    return count, float(gpus_per_worker), free


@dataclasses.dataclass
class _Slot:
    number: int
    label: str
    handle: object
    restarts: int = 0
    alive: bool = True
    busy: bool = False


class Cluster:
    """`workers` RenderWorker actors on a Ray cluster (see the module docstring).

    `address`: an existing Ray cluster ("auto", "host:6379", "ray://..."); None starts a local
    one unless Ray is already initialised in this process (then that one is used).
    `gpus_per_worker`: Ray GPUs per worker (None: 1 if the cluster has a GPU per worker, else a
    share of them, 0 without GPUs). `same_node`: put every worker on this driver's node (the
    host-local frame split). `max_attempts`: workers a share may fail on. `ray_init`: extra
    ray.init() keywords for a cluster this object starts."""

    def __init__(self, workers: int | None = None, address: str | None = None, gpus_per_worker: float | None = None,
                 same_node: bool = False, max_attempts: int = 3, max_restarts: int = 2, ray_init: dict | None = None):
        ray = require_ray("--workers" if workers else "rayvr.cluster")
        self._ray = ray
        self._owns_ray = False
        if not ray.is_initialized():
            kwargs = {"include_dashboard": False, "log_to_driver": False, "logging_level": "error",
                      **(ray_init or {})}
            try:
                ray.init(address=address, **kwargs)
            except (ConnectionError, RuntimeError, ValueError) as exc:
                where = f"the Ray cluster at --address {address}" if address else "a local Ray"
                raise ClusterError(f"cannot start or reach {where}: {exc}; check the address "
                                   f"(ray status on the head node) or leave --address out for a local one") from None
            self._owns_ray = True
        count, gpus_per_worker, free = worker_shares(ray, workers, gpus_per_worker)
        self.cluster_gpus = float(ray.cluster_resources().get("GPU", 0.0))
        self.gpus_per_worker = float(gpus_per_worker)
        # CPUs only place the workers (llvmpipe uses every core anyway): what is free, shared.
        self.cpus_per_worker = min(1.0, float(free.get("CPU", 0.0)) / count)
        self.max_attempts = int(max_attempts)
        self.max_restarts = int(max_restarts)
        options = {"num_gpus": self.gpus_per_worker, "num_cpus": self.cpus_per_worker, "max_restarts": 0}
        if same_node:
            from ray.util.scheduling_strategies import NodeAffinitySchedulingStrategy

            options["scheduling_strategy"] = NodeAffinitySchedulingStrategy(ray.get_runtime_context().get_node_id(),
                                                                            soft=False)
        self._actor = ray.remote(RenderWorker).options(**options)
        self._counter = ray.remote(ProgressCounter).options(num_cpus=0).remote()
        self._scenes: dict = {}
        self._jobs = itertools.count()
        self.slots = [self._start(i) for i in range(count)]
        self.infos = self._wait_started(self.slots)

    # -- workers ---------------------------------------------------------------------------------
    def _start(self, number: int, restarts: int = 0) -> _Slot:
        label = f"worker {number}" + (f".{restarts}" if restarts else "")
        return _Slot(number, label, self._actor.remote(label, self._counter), restarts)

    def _wait_started(self, slots) -> list[dict]:
        ray = self._ray
        refs = [s.handle.info.remote() for s in slots]
        ready, pending = ray.wait(refs, num_returns=len(refs), timeout=START_TIMEOUT_S)
        if pending:
            self._kill_all()
            raise ClusterError(f"{len(pending)} of {len(refs)} workers did not start within {START_TIMEOUT_S:g} s "
                               f"(resources: {ray.cluster_resources()}); ask for fewer workers")
        try:
            return ray.get(refs)
        except ray.exceptions.RayActorError as exc:
            self._kill_all()
            raise ClusterError(f"a worker could not start: {_cause_text(exc)}") from None

    def _replace(self, slot: _Slot) -> None:
        self.slots[self.slots.index(slot)] = self._start(slot.number, slot.restarts + 1)

    def _ensure_workers(self) -> None:
        """A job starts with every worker: replace those an earlier job lost or stopped."""
        for slot in list(self.slots):
            if not slot.alive:
                self._replace(slot)

    def _kill(self, slot: _Slot) -> None:
        slot.alive = False
        slot.busy = False
        try:
            self._ray.kill(slot.handle, no_restart=True)
        except Exception:   # already gone
            pass

    def _kill_all(self) -> None:
        for slot in getattr(self, "slots", []):
            if slot.alive:
                self._kill(slot)

    @property
    def handles(self) -> list:
        """The live workers' actor handles (for tests: ray.kill one)."""
        return [s.handle for s in self.slots if s.alive]

    @property
    def size(self) -> int:
        """Live workers."""
        return sum(1 for s in self.slots if s.alive)

    def describe(self) -> str:
        """One line per worker: label, GPU, renderer, host."""
        return "\n".join(f"{i['label']}: GPU {','.join(i['gpu_ids']) or '-'}, EGL device {i['egl_device']}, "
                         f"{i['renderer']} on {i['host']}" for i in self.infos)

    # -- scenes ------------------------------------------------------------------------------------
    def scene_ref(self, scene, effects: dict | None = None) -> tuple:
        """(key, [ObjectRef]) of `scene` (a Scene, glTF path, built-in name or ScenePayload),
        put into the object store once; pass it to `run`."""
        payload = ScenePayload.of(scene, effects)
        key = payload.key
        if key not in self._scenes:
            self._scenes[key] = self._ray.put(payload)
        return key, [self._scenes[key]]

    def put(self, value):
        """`ray.put(value)`: a large argument (a reference image) shared by many shares."""
        return self._ray.put(value)

    # -- running a job -----------------------------------------------------------------------------
    def run(self, shares: list[Share], scene=None, on_result=None, desc: str = "job", unit: str = "frame",
            progress: bool = True) -> list:
        """Run every share on the workers; `on_result(share, result)` sees each result as it
        arrives (any order), else the results are returned in share order. See the module
        docstring for faults, Ctrl-C and progress."""
        ray = self._ray
        faults = (ray.exceptions.RayActorError, ray.exceptions.ActorUnavailableError,
                  ray.exceptions.WorkerCrashedError, ray.exceptions.ObjectLostError)
        self._ensure_workers()
        job = next(self._jobs)
        queue = collections.deque(sorted(shares, key=lambda s: s.index))
        results: dict = {}
        inflight: dict = {}
        bar = JobBar(desc, sum(s.work for s in shares), unit, progress)
        last_poll = 0.0
        last_error = None
        try:
            while queue or inflight:
                for slot in self.slots:
                    share = self._next_share(queue, slot) if slot.alive and not slot.busy else None
                    if share is not None:
                        ref = slot.handle.run.remote(share.method, scene, (job, share.index), **share.kwargs)
                        inflight[ref] = (share, slot)
                        slot.busy = True
                if not inflight:
                    raise ClusterError(f"{desc}: every worker died ({len(self.slots)} started); "
                                       f"last error: {last_error or 'none reported'}")
                ready, _ = ray.wait(list(inflight), num_returns=1, timeout=POLL_S)
                for ref in ready:
                    share, slot = inflight.pop(ref)
                    slot.busy = False
                    try:
                        result = ray.get(ref)
                    except faults as exc:
                        last_error = self._fault(job, share, slot, _cause_text(exc), queue)
                        continue
                    except ray.exceptions.RayTaskError as exc:
                        cause = getattr(exc, "cause", None)
                        if isinstance(cause, GpuError):   # a lost or broken GPU: another worker
                            last_error = self._fault(job, share, slot, str(cause), queue)
                            continue
                        if isinstance(cause, RayvrError):
                            raise cause from None
                        raise
                    if on_result is not None:
                        on_result(share, result)
                    else:
                        results[share.index] = result
                now = time.perf_counter()
                if progress and now - last_poll >= POLL_S:
                    bar.show(ray.get(self._counter.total.remote(job)))
                    last_poll = now
            bar.show(sum(s.work for s in shares))
        except BaseException:
            # Ctrl-C or a failed job: stop the workers still rendering for it.
            for share, slot in inflight.values():
                self._kill(slot)
            raise
        finally:
            bar.close()
            self._counter.clear.remote(job)
        return [results[i] for i in sorted(results)] if on_result is None else []

    def _next_share(self, queue, slot: _Slot) -> Share | None:
        """The first queued share `slot` may take: one for any worker, for it, or for a dead one."""
        alive = {s.number for s in self.slots if s.alive}
        for share in queue:
            if share.slot is None or share.slot == slot.number or share.slot not in alive:
                queue.remove(share)
                return share
        return None

    def _fault(self, job, share: Share, slot: _Slot, error: str, queue) -> str:
        """A worker died under `share`: replace it, put the share back (front of the queue)."""
        self._kill(slot)
        if slot.restarts < self.max_restarts:
            self._replace(slot)
        self._counter.reset.remote((job, share.index))
        share.attempts += 1
        if share.attempts >= self.max_attempts:
            raise ClusterError(f"share {share.index} ({share.method}) failed on {share.attempts} workers; "
                               f"last error: {error}")
        queue.appendleft(share)
        return f"{slot.label}: {error}"

    def call(self, method: str, scene=None, desc: str = "job", progress: bool = False, **kwargs):
        """One share on one worker (re-run elsewhere if that worker dies); its result."""
        return self.run([Share(0, method, kwargs)], scene, desc=desc, progress=progress)[0]

    # -- life ----------------------------------------------------------------------------------------
    def close(self) -> None:
        """Kill the workers (and stop Ray if this object started it)."""
        self._kill_all()
        try:
            self._ray.kill(self._counter)
        except Exception:
            pass
        if self._owns_ray:
            self._ray.shutdown()
            self._owns_ray = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _cause_text(exc) -> str:
    """A one-line reason from a Ray exception (its cause where it has one)."""
    cause = getattr(exc, "cause", None) or getattr(exc, "error_msg", None) or exc
    return " ".join(str(cause).split())[:300]


class using:
    """`with using(cluster, workers, address) as c`: the given Cluster, or a new one closed
    at the end of the block."""

    def __init__(self, cluster: Cluster | None = None, workers: int | None = None, address: str | None = None,
                 **kwargs):
        self._given = cluster
        self._args = (workers, address, kwargs)
        self._made = None

    def __enter__(self) -> Cluster:
        if self._given is not None:
            return self._given
        workers, address, kwargs = self._args
        self._made = Cluster(workers, address, **kwargs)
        return self._made

    def __exit__(self, *exc):
        if self._made is not None:
            self._made.close()
