"""One vocabulary (issue 22): target, threshold = target - eps_tol, reached; and a
plain verification verdict."""

from ideas_hpc.campaign.vocabulary import requirement_line, verification_verdict


def test_requirement_line_names_the_three_numbers():
    s = requirement_line(0.99837, 0.99837 - 0.001, 0.99781)
    assert s == ("target 99.837 %, threshold 99.737 % (target - eps_tol), reached 99.781 %")
    low = requirement_line(1.0, 0.999, 0.99)
    assert low.endswith("reached 99.000 % (below the threshold)")


def test_verdict_against_a_required_probability():
    assert verification_verdict(0.875, 64, 0.9974, 0.9).startswith("verification FAILED")
    assert verification_verdict(0.9, 64, 0.9974, 0.9).startswith("verification PASSED")
    assert "required 90.0 %" in verification_verdict(0.95, 64, 0.9974, 0.9)


def test_verdict_without_requirement_passes_only_when_every_sample_reaches():
    # a design sized for the nominal flight claims the threshold: one miss fails it
    s = verification_verdict(3 / 64, 64, 0.9974)
    assert s.startswith("verification FAILED") and "4.7 % of 64" in s
    assert verification_verdict(63 / 64, 64, 0.9974).startswith("verification FAILED")
    assert verification_verdict(1.0, 64, 0.9974).startswith("verification PASSED")
