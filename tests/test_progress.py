"""Progress bars of the long phases (issue 22): shown on stderr, off with --no-progress,
results in order."""

from ideas_hpc.base import progress


def test_map_chunks_bar_and_order(capsys):
    with progress.enabled(True):
        out = progress.map_chunks(lambda c: [x * x for x in c], [[1, 2], [3], [4]],
                                  desc="verification")
    assert out == [[1, 4], [9], [16]]
    err = capsys.readouterr().err
    assert "verification" in err and "/3 " in err


def test_no_bar_when_disabled_or_without_desc(capsys):
    with progress.enabled(False):
        assert list(progress.steps(range(3), "coverage vs N")) == [0, 1, 2]
    progress.map_chunks(len, [[1], [2, 3]], desc=None)
    assert capsys.readouterr().err == ""


def test_map_chunks_retries_and_returns_or_raises_failures():
    """The one chunk executor: a chunk that raised runs again ``retries`` times; one that
    still fails is returned as its exception (the engine records it) or raised."""
    import pytest

    calls = {}

    def flaky(c):
        calls[c] = calls.get(c, 0) + 1
        if c == "bad" or (c == "once" and calls[c] == 1):
            raise RuntimeError(f"chunk {c}")
        return c.upper()

    out = progress.map_chunks(flaky, ["a", "once", "bad"], desc=None, retries=1,
                              errors="return")
    assert out[:2] == ["A", "ONCE"] and isinstance(out[2], RuntimeError)
    assert calls == {"a": 1, "once": 2, "bad": 2}
    with pytest.raises(RuntimeError, match="chunk bad"):
        progress.map_chunks(flaky, ["bad"], desc=None)
