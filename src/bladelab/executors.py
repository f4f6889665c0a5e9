"""Executors that run independent tasks: in-process, a local process pool, or Ray.

Every executor takes a *top-level* (importable, picklable) function ``task(payload) -> dict`` and
a list of picklable payloads, and yields ``(index, status, value)`` as tasks finish, in any order:
``status`` is ``"ok"`` (value = the task's dict) or ``"failed"`` (value = an error message). A task
that raises never stops the others. The list may grow while the results are read: payloads
appended to it (a list) are submitted as soon as the loop asks for the next result, so that a
caller can hand out work that becomes ready as earlier tasks finish (no idle worker waiting for
a whole round to end).

- :class:`SerialExecutor`: in this process (``jobs=1``).
- :class:`LocalExecutor`: ``concurrent.futures.ProcessPoolExecutor`` with the ``forkserver`` start
  method on Linux (``spawn`` elsewhere); safe with numba's threads and Ray's, unlike ``fork``.
- :class:`RayExecutor`: Ray (optional extra ``pip install bladelab[ray]``, imported lazily); starts a
  local instance ``ray.init(num_cpus=jobs, include_dashboard=False)`` unless one is running, and
  gives the workers the driver's ``sys.path``.

:class:`ProcessPool` is the persistent local pool underneath, for callers that submit many
rounds of work to the same workers (CMA-ES generations, :mod:`bladelab.predict.reflex.optimize`).
Used by :mod:`bladelab.study`, :mod:`bladelab.predict` and :mod:`bladelab.design`.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import traceback
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any

from bladelab.errors import BladelabError

Task = Callable[[dict], dict]


#: Set in the worker processes of a :class:`ProcessPool` (:func:`_mark_pool_worker`).
_IN_POOL_WORKER = False


def _mark_pool_worker() -> None:
    """Initializer of a pool's workers."""
    global _IN_POOL_WORKER
    _IN_POOL_WORKER = True


def run_task_safely(task: Task, payload: dict) -> tuple[str, Any]:
    """Run ``task(payload)``; return ("ok", result) or ("failed", one-line message).

    In a pool's worker an interrupt ends the worker process once the task's own clean-up
    has run: ``concurrent.futures`` would otherwise send the KeyboardInterrupt back as a result
    and start the next queued task (a collocation solve turns the pool's SIGTERM into one)."""
    try:
        return "ok", task(payload)
    except KeyboardInterrupt:
        if _IN_POOL_WORKER:
            os._exit(143)
        raise
    except BladelabError as err:
        return "failed", str(err)
    except Exception as err:  # noqa: BLE001 - a failing trial must not stop the study
        last = traceback.extract_tb(err.__traceback__)[-1] if err.__traceback__ else None
        where = f" ({os.path.basename(last.filename)}:{last.lineno})" if last else ""
        return "failed", f"{type(err).__name__}: {err}{where}"


class SerialExecutor:
    """Run tasks one after the other in this process."""

    name = "serial"

    def __init__(self, jobs: int = 1) -> None:
        self.jobs = 1

    def run(self, task: Task, payloads: Sequence[dict]) -> Iterator[tuple[int, str, Any]]:
        i = 0
        while i < len(payloads):  # the list may grow (module docstring)
            status, value = run_task_safely(task, payloads[i])
            yield i, status, value
            i += 1


def default_start_method() -> str:
    """``forkserver`` on Linux (safe with numba's and Ray's threads, unlike ``fork``), else
    ``spawn``."""
    return "forkserver" if sys.platform.startswith("linux") else "spawn"


#: Seconds a terminated worker has to finish its clean-up before it is killed.
TERMINATE_GRACE_S = 5.0


def terminate_pool(pool) -> None:
    """Stop a ``ProcessPoolExecutor``'s workers now (an interrupted run): without this, workers
    busy with long tasks outlive a killed parent and go on writing to its output folder."""
    procs = [p for p in (getattr(pool, "_processes", None) or {}).values() if p.is_alive()]
    for proc in procs:
        proc.terminate()
    for proc in procs:  # a worker that outlives its grace period is killed
        proc.join(TERMINATE_GRACE_S)
        if proc.is_alive():
            proc.kill()
    # no cancel_futures: the broken pool fails its queued futures itself, and Python 3.11's
    # manager thread raised InvalidStateError (a traceback on stderr) on cancelled ones
    pool.shutdown(wait=True)


class ProcessPool:
    """A persistent pool of ``jobs`` local worker processes; a context manager that stops busy
    workers at once when its block raises (Ctrl-C, SIGTERM via the CLI, an error)."""

    def __init__(self, jobs: int, *, start_method: str | None = None) -> None:
        ctx = multiprocessing.get_context(start_method or default_start_method())
        self.jobs = int(jobs)
        self._pool = ProcessPoolExecutor(max_workers=self.jobs, mp_context=ctx,
                                         initializer=_mark_pool_worker)

    def submit(self, fn: Callable, *args: Any):
        """Run ``fn(*args)`` in a worker; returns its ``concurrent.futures.Future``."""
        return self._pool.submit(fn, *args)

    def map(self, fn: Callable, items: Sequence) -> list:
        """``[fn(item) for item in items]`` on the workers, in order (a worker's error raises)."""
        return list(self._pool.map(fn, items))

    def close(self, *, abort: bool = False) -> None:
        """Shut the pool down; ``abort`` stops busy workers at once."""
        if abort:
            terminate_pool(self._pool)
        else:
            self._pool.shutdown()

    def __enter__(self) -> ProcessPool:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(abort=exc_type is not None)


class LocalExecutor:
    """A local process pool of ``jobs`` workers."""

    name = "local"

    def __init__(self, jobs: int = 2, *, start_method: str | None = None) -> None:
        if jobs < 1:
            raise BladelabError(f"--jobs {jobs}: need at least 1", where="jobs")
        self.jobs = int(jobs)
        self.start_method = start_method or default_start_method()

    def run(self, task: Task, payloads: Sequence[dict]) -> Iterator[tuple[int, str, Any]]:
        if not payloads:
            return
        with ProcessPool(min(self.jobs, len(payloads)), start_method=self.start_method) as pool:
            pending = {}

            def submit_new() -> None:  # the list may grow (module docstring)
                for i in range(len(pending) + done, len(payloads)):
                    pending[pool.submit(run_task_safely, task, payloads[i])] = i

            done = 0
            submit_new()
            try:
                while pending:
                    finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                    for fut in finished:
                        i = pending.pop(fut)
                        done += 1
                        try:
                            status, value = fut.result()
                        except Exception as err:  # noqa: BLE001 - a worker died
                            status, value = "failed", f"worker failed: {type(err).__name__}: {err}"
                        yield i, status, value
                        submit_new()
            finally:
                if pending:  # interrupted (Ctrl-C, SIGTERM via the CLI, an error)
                    pool.close(abort=True)


class RayExecutor:
    """Ray tasks on a local (or already running) Ray instance."""

    name = "ray"

    def __init__(self, jobs: int = 2) -> None:
        try:
            import ray  # noqa: F401  # deferred: ray is an optional extra
        except ImportError:
            raise BladelabError(
                "the Ray executor needs the 'ray' package, which is not installed",
                where="executor", hint="pip install 'bladelab[ray]', or use --executor local",
            ) from None
        self.jobs = int(jobs)

    def run(self, task: Task, payloads: Sequence[dict]) -> Iterator[tuple[int, str, Any]]:
        import ray  # deferred: ray is an optional extra

        if not payloads:
            return
        started = start_local_ray(self.jobs)
        try:
            remote = ray.remote(num_cpus=1)(run_task_safely)
            refs = {}
            submitted = 0
            while True:
                for i in range(submitted, len(payloads)):  # the list may grow
                    refs[remote.remote(task, payloads[i])] = i
                submitted = len(payloads)
                if not refs:
                    break
                ready, _ = ray.wait(list(refs), num_returns=1)
                for ref in ready:
                    i = refs.pop(ref)
                    try:
                        status, value = ray.get(ref)
                    except Exception as err:  # noqa: BLE001 - a worker died
                        status, value = "failed", f"ray task failed: {type(err).__name__}: {err}"
                    yield i, status, value
        finally:
            if started:
                ray.shutdown()


def start_local_ray(num_cpus: int) -> bool:
    """Start a quiet local Ray instance with ``num_cpus`` CPUs, its workers on this process's
    ``sys.path``, unless one is running; True when this call started it."""
    import ray  # deferred: ray is an optional extra

    if ray.is_initialized():
        return False
    ray.init(
        num_cpus=num_cpus, include_dashboard=False, log_to_driver=False,
        logging_level="ERROR", configure_logging=False,
        runtime_env={"env_vars": {"PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}},
    )
    return True


def make_executor(name: str, jobs: int = 1):
    """``"local"`` (a process pool; in-process when ``jobs == 1``), ``"serial"`` or ``"ray"``."""
    if name == "local":
        return SerialExecutor() if jobs <= 1 else LocalExecutor(jobs)
    if name == "serial":
        return SerialExecutor()
    if name == "ray":
        return RayExecutor(max(1, jobs))
    raise BladelabError(f"unknown executor {name!r}", where="executor", hint="use 'local' or 'ray'")


def say_to_stderr(line: str) -> None:
    """A task's progress line, on standard error (above the parent's progress bar)."""
    print(f"  {line}", file=sys.stderr, flush=True)


__all__ = [
    "LocalExecutor",
    "ProcessPool",
    "RayExecutor",
    "SerialExecutor",
    "default_start_method",
    "make_executor",
    "run_task_safely",
    "say_to_stderr",
    "start_local_ray",
    "terminate_pool",
]
