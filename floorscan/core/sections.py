"""A stage's config section for one dataset, and the checks of one key against another.

A dataset may override a stage's keys (``datasets.<name>.params.<stage>``):
:func:`dataset_section` merges them over the global section, which is what the workflow
passes to the stage's jobs through ``params:`` (``stage_config`` in
``workflow/rules/common.smk``), so a changed value reruns the stage.

The schemas judge each value alone. :func:`check_sections` judges the values that
depend on another key (``select.default_ordering`` must be one of ``walls.orderings``),
for the global sections and for every dataset's merged ones. The workflow calls it
once, when the config is loaded (``workflow/rules/common.smk``), so a bad pair stops
the run before any job is planned and the rules' ``params:`` are the plain sections.
:func:`evaluation_grid_errors` judges what only the evaluation needs of ``walls.k``.

To add a check: one more test in :func:`section_errors`, with a message naming both
keys and what is expected.
"""

from __future__ import annotations

import copy
from typing import Any, Iterable, Mapping

from floorscan.core.config import ConfigError


def merge_override(base: Mapping | None, override: Mapping | None) -> dict:
    """A deep copy of ``base`` with ``override`` merged over it: mappings key by key,
    any other value (a list too) replaced. Neither argument is changed.

    Parameters
    ----------
    base, override : mapping or None
        None is an empty mapping.

    Returns
    -------
    dict
    """
    out = copy.deepcopy(dict(base or {}))
    for key, value in (override or {}).items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge_override(out[key], value)
        else:
            out[key] = copy.deepcopy(value)
    return out


def dataset_section(config: Mapping, dataset: str, stage: str) -> dict:
    """The ``stage`` section of ``config`` for ``dataset``: its
    ``datasets.<dataset>.params.<stage>`` overrides merged over the global section
    (:func:`merge_override`).

    Parameters
    ----------
    config : mapping
        The workflow config.
    dataset : str
    stage : str
        A section name, e.g. ``"walls"``.

    Returns
    -------
    dict
        A new dict; ``config`` is not changed.

    Raises
    ------
    KeyError
        When ``config`` has no dataset ``dataset``.
    """
    ds = config["datasets"][dataset]
    return merge_override(config.get(stage, {}), (ds.get("params") or {}).get(stage))


def section_errors(sections: Mapping[str, Mapping[str, Any]], extractors: Iterable[str]) -> list[str]:
    """What is wrong in one set of stage sections, a key against another.

    Parameters
    ----------
    sections : mapping
        Stage name -> its section after validation (defaults filled): ``walls``,
        ``select``, ``floorplan`` and ``score`` are read.
    extractors : iterable of str
        The registered wall extractors (``floorscan.walls.extractors.REGISTRY``).

    Returns
    -------
    list of str
        One message per problem, in the order of the checks; empty when all agree.
    """
    walls, select = sections["walls"], sections["select"]
    floorplan, score = sections["floorplan"], sections["score"]
    registered = list(extractors)
    errors = []
    unknown = [e for e in walls["extractors"] if e not in registered]
    if unknown:
        errors.append(
            f"walls.extractors names {unknown}, which are not registered in floorscan.walls.extractors; "
            f"registered: {registered}"
        )
    wall_extractors, orderings = list(walls["extractors"]), list(walls["orderings"])
    coverage_extractor = select["coverage"]["wall_extractor"]
    if coverage_extractor not in wall_extractors:
        errors.append(
            f"select.coverage.wall_extractor {coverage_extractor!r} is not one of walls.extractors {wall_extractors}"
        )
    if select["default_ordering"] not in orderings:
        errors.append(f"select.default_ordering {select['default_ordering']!r} is not one of walls.orderings {orderings}")
    if floorplan["extractor"] != "map" and floorplan["extractor"] not in wall_extractors:
        errors.append(
            f"floorplan.extractor {floorplan['extractor']!r} is neither map nor one of walls.extractors {wall_extractors}"
        )
    taus = [float(t) for t in score["taus_m"]]
    if not any(abs(float(score["summary_tau_m"]) - t) < 1e-12 for t in taus):
        errors.append(f"score.summary_tau_m {score['summary_tau_m']} is not in score.taus_m {taus}")
    return errors


def evaluation_grid_errors(score: Mapping[str, Any], walls_k: Iterable) -> list[str]:
    """What the evaluation's figures and summary miss in ``walls.k``: the k of
    ``score.figure_k`` and "all" (the summary compares with the all-scan F1).

    Both keys name files (the same for every dataset), so this is checked on the global
    sections. The workflow reports it only when it plans an evaluation job: a run that
    narrows ``walls.k`` to build some plans needs neither.

    Parameters
    ----------
    score : mapping
        The ``score`` section (``figure_k``).
    walls_k : iterable
        ``walls.k``: ints and/or ``"all"``.

    Returns
    -------
    list of str
        One message per problem; empty when ``walls.k`` holds both.
    """
    ks = [str(k) for k in walls_k]
    errors = []
    if str(score["figure_k"]) not in ks:
        errors.append(f"score.figure_k {score['figure_k']} is not in walls.k {ks}")
    if "all" not in ks:
        errors.append("walls.k must contain 'all': the summary compares with the all-scan F1")
    return errors


def check_sections(config: Mapping, extractors: Iterable[str]) -> None:
    """Check the global sections and every dataset's (:func:`dataset_section`) with
    :func:`section_errors`.

    Parameters
    ----------
    config : mapping
        The workflow config (``walls``, ``select``, ``floorplan``, ``score``,
        ``datasets``).
    extractors : iterable of str
        The known wall extractors.

    Raises
    ------
    ConfigError
        The first problem: of the global sections as it is, of a dataset's after
        ``datasets.<name>.params: `` (the dataset's overrides make it).
    """
    stages = ("walls", "select", "floorplan", "score")
    extractors = list(extractors)
    errors = section_errors({stage: config[stage] for stage in stages}, extractors)
    if errors:
        raise ConfigError(errors[0])
    for name in config["datasets"]:
        errors = section_errors({stage: dataset_section(config, name, stage) for stage in stages}, extractors)
        if errors:
            raise ConfigError(f"datasets.{name}.params: {errors[0]}")
