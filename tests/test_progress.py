"""Progress bars of the long phases (issue 22): shown on stderr, off with --no-progress,
results in order."""

from ideas_hpc import progress


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
