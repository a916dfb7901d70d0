"""shakedown.model.threads: one BLAS thread inside, the previous limits restored after."""

from threadpoolctl import threadpool_info, threadpool_limits

from shakedown.model.threads import single_blas_thread


def _blas_threads():
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_single_blas_thread_limits_and_restores():
    with threadpool_limits(limits=2, user_api="blas"):
        before = _blas_threads()
        assert before and all(t == min(2, t) for t in before)
        with single_blas_thread():
            assert _blas_threads() == [1] * len(before)
        assert _blas_threads() == before


def test_solve_cycles_runs_with_one_blas_thread(monkeypatch):
    """The cyclic runs hold the limit while they run (seen from inside a step)."""
    import numpy as np

    import shakedown as sd
    from shakedown.evolution import fast_period

    seen = []
    real = fast_period.run_period

    def spy(*a, **k):
        seen.append(_blas_threads())
        return real(*a, **k)

    monkeypatch.setattr(fast_period, "run_period", spy)
    s = sd.DiscreteSystem([[2.0, 0.3], [0.3, 2.0]], np.zeros((2, 2)), np.eye(2), friction=0.5)
    load = sd.LoadCycle.from_harmonics([0.0, 0.0], [1.0, 1.0], q_cos=[1.0, -1.0])
    with threadpool_limits(limits=2, user_api="blas"):
        sd.solve_cycles(s, load, 1.0, steps_per_cycle=8)
    assert seen and all(t == [1] * len(t) for t in seen)
