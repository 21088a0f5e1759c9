"""Issue 35's Done-when: the corpus of bad and unusual recordings of
``benchmarks/bench_bad_input.py`` (issue 35's classes, a few older ones, good controls),
each run through ingest, poses and register: none ends silent (a wrong or partial
result and nothing said), at most two are unclear (an error that does not name the
file and the field, topic or frame, or a bug's traceback)."""

import pytest

from benchmarks.bench_bad_input import cases, run_corpus, tally, tally_line


@pytest.mark.slow
def test_bad_recordings_end_in_a_clear_error_or_a_run_that_says_what_was_lost(tmp_path):
    corpus = cases()
    assert len(corpus) >= 40 and sum(c.issue for c in corpus) >= 30
    lines: list[str] = []
    outcomes = run_corpus(tmp_path, corpus, echo=lines.append)
    print("\n".join(lines) + "\n" + tally_line(outcomes))  # shown with pytest -s, or on failure
    counts = tally(outcomes)
    failing = "\n".join(f"{o.outcome} {o.case.name}: {o.detail}" for o in outcomes
                        if o.outcome in ("silent", "unclear"))
    assert counts["silent"] == 0 and counts["unclear"] <= 2, f"{tally_line(outcomes)}\n{failing}"
    # the controls run as they should
    assert all(o.outcome == "correct" for o in outcomes if o.case.name.startswith("good_")), failing
