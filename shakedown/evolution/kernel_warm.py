"""When the compiled kernel is used: compiled now, loaded from numba's cache, or (the command
line's first run) compiled in the background while the steps run in Python (issue 25).

Compiling the kernel (:mod:`.kernel`: the period loop ``march`` and everything it calls) costs
about 70 s of CPU once after installing (``benchmarks/RESULTS_first_run.md``); numba then keeps
it on disk (``cache=True``: beside the package in ``shakedown/evolution/__pycache__``, or in
``NUMBA_CACHE_DIR``) and later processes load it in about 0.5 s.  Its entries are stamped by
the contents of all the kernel's source files (:data:`.kernel_jit.KERNEL_SOURCES`): after an
edit of any of them, :func:`cached` answers False and the whole kernel is compiled again once.
The policy for a process whose cache is cold is read from the environment variable
``SHAKEDOWN_KERNEL`` each time it is asked:

- unset or ``compile``: compile at the first use (the library's default; a study's workers
  load what the parent compiled, :func:`warm_up`);
- ``background`` (what ``shakedown run`` and the other commands set for their own processes):
  if the cache does not hold the kernel, solvers made now run every step in Python
  (:meth:`~.complementarity.StepSolver.solve`: the same step, verified by the same checks; the
  default scene's answers agree with the kernel's to 5e-13 relative, its discrete outcomes
  exactly) and one detached, low-priority process compiles the kernel into the cache
  (:func:`main`, one at a time: a lock file); solvers made
  after it has finished use the kernel;
- ``numpy`` (or ``python``, ``off``, ``0``): never the kernel (:mod:`.kernel_jit`).

The decision is taken when a :class:`~.complementarity.StepSolver` is made
(:func:`kernel_enabled`), so one solver, hence one run or one study task, never mixes the two
paths; the tasks of a study that straddles the end of the background compile can (their rows then
agree to round-off, not bit for bit, with those of a run on a warm cache).  The cache is
checked by asking numba's own cache for the exact argument types of the kernel's calls
(:func:`kernel_args`; every call site passes the same types, so that one signature is compiled,
not one per array flag or layout).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from . import kernel as _k
from . import kernel_shortcut as _ks

#: Environment variable naming the policy (see the module docstring).
POLICY_VAR = "SHAKEDOWN_KERNEL"
#: Seconds between two looks at the cache while it is cold (background policy).
RECHECK_SECONDS = 2.0
#: A lock file older than this (seconds) is stale (its compiling process died).
LOCK_STALE_SECONDS = 900.0

_state = {"ready": False, "checked": -np.inf, "started": None}


class KernelCache:
    """Storage of the kernel's inverse cache for one system (``cache_bytes`` bounds the pool
    of inverses; when full the cache keeps the last period's answers, drops the rest and is
    refilled: :func:`.kernel_cache._compact`).  It also keeps the last period's assignments as
    the prediction of the next period with the same load (:meth:`prediction`)."""

    def __init__(self, n: int, cache_bytes: float, max_iter: int):
        self.n = n
        # room for 128 of the largest inverses ((2N)^2 numbers each; typical ones are 16x
        # smaller) within the budget, and always for one: a small system does not reserve
        # the whole budget
        n_doubles = max(min(int(cache_bytes // 8), 128 * (2 * n) ** 2), (2 * n) ** 2)
        self.pool = np.empty(n_doubles)  # pages are touched only as inverses are stored
        slots = int(min(4096, max(64, n_doubles // max(n, 1))))
        self.keys = np.zeros((slots, n), np.int8)
        self.hashes = np.zeros(slots, np.uint64)
        # pool offset, index offset, updates, step it answered last (kernel_cache.stamp)
        self.offs = np.zeros((slots, 4), np.int64)
        self.sizes = np.zeros(slots, np.int64)
        self.ipool = np.zeros(slots * 2 * n if slots * 2 * n <= 8_000_000 else 8_000_000,
                              np.int64)
        self.fpool = np.zeros(self.ipool.size)
        self.meta = np.zeros(8, np.int64)
        self.meta[3] = -1  # no last solved assignment
        self.counters = np.zeros(8, np.int64)
        self.seen = np.zeros((max_iter + 1, n), np.int8)
        rng = np.random.default_rng(20261123)
        self.mult = rng.integers(1, 2**63 - 1, size=n, dtype=np.int64).astype(np.uint64) | 1
        self._shortcut = None
        self._pred = None

    def prediction(self, qw: np.ndarray, pw: np.ndarray) -> np.ndarray:
        """The assignments ``(n_steps, N)`` of the last period completed with the welded
        reactions ``qw, pw`` (:meth:`keep_prediction`), or an empty ``(0, N)`` array."""
        c = self._pred
        if (c is not None and c[0].shape == qw.shape and np.array_equal(c[0], qw)
                and np.array_equal(c[1], pw)):
            return c[2]
        return np.zeros((0, self.n), np.int8)

    def keep_prediction(self, qw: np.ndarray, pw: np.ndarray, act: np.ndarray) -> None:
        """Keep a completed period's assignments ``act`` (n_steps, N) as the prediction of
        the next period with the same ``qw, pw`` (the kernel's :func:`~.kernel._probe`)."""
        c = self._pred
        if c is None or c[0].shape != qw.shape or not (np.array_equal(c[0], qw)
                                                       and np.array_equal(c[1], pw)):
            c = (qw.copy(), pw.copy(), np.empty(act.shape, np.int8))
            self._pred = c
        c[2][:] = act

    def shortcut_state(self, qw: np.ndarray, pw: np.ndarray):
        """:func:`.kernel_shortcut.state` of a period's welded reactions, kept for the next
        periods with the same ``qw, pw`` (its basis costs ~0.3 ms at N = 100, a fifth of a
        period there)."""
        c = self._shortcut
        if (c is not None and c[0].shape == qw.shape and np.array_equal(c[0], qw)
                and np.array_equal(c[1], pw)):
            return c[2]
        st = _ks.state(self.n, qw, pw)
        self._shortcut = (qw.copy(), pw.copy(), st)
        return st


def policy() -> str:
    """``"off"``, ``"background"`` or ``"compile"`` (from ``SHAKEDOWN_KERNEL``)."""
    v = os.environ.get(POLICY_VAR, "").strip().lower()
    if not _k.HAVE_KERNEL or v in ("numpy", "python", "off", "0"):
        return "off"
    return "background" if v == "background" else "compile"


def readonly(a) -> np.ndarray:
    """A read-only C-contiguous float view (copy if needed): the one array type the kernel is
    compiled for, whatever the caller's flags and layout (numba types a read-only or strided
    array apart, and would compile once per type)."""
    v = np.ascontiguousarray(a, float).view()
    v.setflags(write=False)
    return v


def writable(a, dtype=float) -> np.ndarray:
    """``a`` as a writable C-contiguous array of ``dtype`` (copied only when it is not one)."""
    return np.require(a, dtype, ["C", "W"])


def kernel_args(n: int = 1):
    """Arguments of one period of an ``n``-node system by :func:`.kernel.march` (a load that
    makes the node slip both ways), and of a direct :func:`.kernel._solve_set` call: ``(march
    args, solve_set args)``, with the types of every real call."""
    K = np.eye(2 * n)
    kc = KernelCache(n, 1e5, 4)
    qw = np.tile(np.array([[-2.0], [2.0]]), (1, n))
    pw = np.ones((2, n))
    V, Wg, Q, P = (np.zeros((3, n)) for _ in range(4))
    st, act = np.zeros((3, n), np.int8), np.zeros((2, n), np.int8)
    cache = (kc.mult, kc.keys, kc.hashes, kc.offs, kc.sizes, kc.pool, kc.ipool, kc.fpool,
             kc.meta, kc.counters)
    march = (readonly(K), readonly(np.full(n, 0.5)), readonly(np.ones(2 * n)), qw, pw, 0,
             qw[0].copy(), pw[0].copy(), np.zeros(n, np.int8), 1e-9, 4, *cache, kc.seen,
             V, Wg, Q, P, st, act, np.zeros(2), np.zeros(2), np.zeros(1),
             *_ks.state(n, qw, pw), np.zeros((0, n), np.int8))
    solve_set = (np.ones(n, np.int8), readonly(K), readonly(np.full(n, 0.5)), qw[0].copy(),
                 pw[0].copy(), n, 1e-9, *cache, np.empty(2 * n), np.empty(n), np.empty(n))
    return march, solve_set


def _signature(disp, args):
    return tuple(disp.typeof_pyval(a) for a in args)


def _load(disp, args) -> bool:
    """Load ``disp``'s compiled code for the types of ``args`` from numba's cache (as numba's
    own ``Dispatcher.compile`` does before compiling); False when it is not there."""
    from numba.core.compiler_lock import global_compiler_lock

    sig = _signature(disp, args)
    with global_compiler_lock:
        if sig in disp.overloads:
            return True
        cres = disp._cache.load_overload(sig, disp.targetctx)
        if cres is None:
            return False
        disp.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
        disp.add_overload(cres)
    return True


def cached() -> bool:
    """The kernel is compiled in this process or loadable from numba's cache (then loaded);
    never compiles."""
    try:
        march, solve_set = kernel_args()
        return _load(_k.march, march) and _load(_k._solve_set, solve_set)
    except (AttributeError, TypeError):  # pragma: no cover - numba's internals changed: no
        return False  # look-up possible, treated as a cold cache


def kernel_enabled() -> bool:
    """Whether a solver made now uses the compiled kernel (the policy above; under
    ``background`` a cold cache starts the background compile and answers False)."""
    p = policy()
    if p == "off":
        return False
    if p == "compile" or _state["ready"]:
        return True
    now = time.monotonic()
    if now - _state["checked"] < RECHECK_SECONDS:
        return False
    _state["checked"] = now
    if cached():
        _state["ready"] = True
        return True
    start_background_compile()
    return False


def lock_path() -> str:
    """The lock file of the background compile (one per Python and package location)."""
    import hashlib

    key = hashlib.sha1(f"{sys.executable}|{os.path.dirname(_k.__file__)}".encode()).hexdigest()
    return os.path.join(tempfile.gettempdir(), f"shakedown-kernel-{key[:12]}.lock")


def _take_lock(path: str) -> bool:
    try:
        if time.time() - os.path.getmtime(path) > LOCK_STALE_SECONDS:
            os.remove(path)
    except OSError:
        pass
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    except OSError:
        return False
    os.close(fd)
    return True


def start_background_compile():
    """Start the detached compiling process unless one runs already (its lock file); the
    process (``subprocess.Popen``) or None."""
    path = lock_path()
    if not _take_lock(path):
        return None
    env = dict(os.environ, **{POLICY_VAR: "compile"})
    kw = dict(stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
              env=env, close_fds=True)
    if os.name == "posix":
        kw.update(start_new_session=True)
    try:
        proc = subprocess.Popen([sys.executable, "-c", "import sys; from shakedown.evolution."
                                 "kernel_warm import main; sys.exit(main(sys.argv[1:]))", path],
                                **kw)
    except OSError:  # pragma: no cover - no process could be started: compile next time
        os.remove(path)
        return None
    _state["started"] = proc
    return proc


def background_note() -> str | None:
    """What the user should be told after a run of this process whose kernel cache was cold
    (None when nothing was started here)."""
    proc, _state["started"] = _state["started"], None
    if proc is None:
        return None
    return ("note: numba's cache did not hold the compiled kernel (first run after installing):"
            " this run's steps ran in Python (the same steps and checks; answers equal to "
            "round-off; solvers made after the kernel was cached use it); a background process "
            f"(pid {proc.pid}) is compiling the kernel (about a minute of CPU) for later runs")


def warm_up() -> float:
    """Compile the kernel (first use after installing, about a minute of CPU, written to numba's
    cache) or load it from the cache (about 0.5 s), once per process; the seconds spent.
    Under the ``background`` policy a cold cache is not compiled here
    (:func:`kernel_enabled`).

    A study calls this before it starts worker processes, so that they load the cache
    instead of compiling the kernel each at the same time.
    """
    t = time.perf_counter()
    p = policy()
    if p == "off":
        return 0.0
    if p == "background":
        kernel_enabled()
        return time.perf_counter() - t
    march, solve_set = kernel_args()
    _k.march(*march)
    _k._solve_set(*solve_set)
    _state["ready"] = True
    return time.perf_counter() - t


def _lower_autogroup(nice: int = 19) -> bool:
    """Lower the scheduling priority of this process's autogroup (Linux, ``sched(7)``); whether
    it was done.

    The background compile starts a new session, and with ``kernel.sched_autogroup_enabled``
    each session is a scheduling group of its own, sharing the CPU equally with the command's
    group whatever the nice value of its one process: measured on a 2-core machine, the
    default study's runs took 12 s instead of 5 s while it compiled.  The group's own nice value
    (``/proc/self/autogroup``) restores the intent: it compiles on idle CPU.  Only done by a
    session leader (the detached process), never to a session it shares with a terminal."""
    if os.getsid(0) != os.getpid():
        return False
    try:
        with open("/proc/self/autogroup", "w") as fh:
            fh.write(str(nice))
        return True
    except OSError:  # no autogroups (other kernels, other systems): the nice value suffices
        return False


def main(argv=None) -> int:
    """The background compile (``python -c "from shakedown.evolution.kernel_warm import main;
    main([LOCK])"``): compile (or load) the kernel, then remove the lock file ``LOCK``."""
    argv = sys.argv[1:] if argv is None else argv
    try:
        if os.name == "posix":
            os.nice(10)
            _lower_autogroup()
        warm_up()
    finally:
        if argv:
            try:
                os.remove(argv[0])
            except OSError:
                pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
