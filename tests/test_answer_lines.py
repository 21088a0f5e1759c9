"""The run's last lines (floorscan.figures.answer): which datasets a run is about."""

from floorscan.figures.answer import answer_lines, run_datasets


def test_the_datasets_of_a_run_follow_its_targets():
    known = ["demo", "intel", "orebro"]
    assert run_datasets([], known, ["demo"]) == ["demo"]
    assert run_datasets(["plan"], known, ["demo", "intel"]) == ["demo", "intel"]
    assert run_datasets(["results/intel/floorplan.svg"], known, ["demo"]) == ["intel"]
    assert run_datasets(["./results/orebro/map.pgm", "results/intel/x"], known, ["demo"]) == ["intel", "orebro"]
    assert run_datasets(["results/unknown/x"], known, ["demo"]) == []


def test_a_failed_dataset_gets_its_error_not_an_older_answer(tmp_path):
    (tmp_path / "a" / "selection").mkdir(parents=True)
    (tmp_path / "a" / "selection" / "selection.json").write_text("{}")  # an older answer: not read
    lines = answer_lines(["a", "b"], tmp_path, failed={"a": "ingest failed: x.bag: truncated"})
    assert lines == [
        "a: FAILED: ingest failed: x.bag: truncated",
        f"b: not finished: no answer yet ({tmp_path}/b/selection/selection.json is not made: the run stopped before "
        "it, or its targets do not include the plan); run it again to go on",
    ]
