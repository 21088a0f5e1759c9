"""The report's front page of a dataset (floorscan.figures.report): the answer on one page;
and summary.md, the answer in Markdown (floorscan.figures.answer)."""
from floorscan.core.stage import stage_log
from floorscan.figures.answer import write_summary_markdown
from floorscan.figures.report import write_front_page_of_files

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    # summary.md first: the page links it when it exists
    write_summary_markdown(smk.output.summary_md, smk.wildcards.dataset, smk.input.selection, smk.input.registration,
                           smk.input.index, evaluation=smk.input.get("evaluation_md"))
    write_front_page_of_files(
        smk.output.front, smk.wildcards.dataset,
        floorplan_svg=smk.input.floorplan_svg, plan=smk.input.plan,
        selection=smk.input.selection, registration=smk.input.registration, index=smk.input.index,
        summary=smk.input.get("summary"), quality_png=smk.input.get("quality_png"),
        extractor=smk.params.extractor, description=smk.params.description, answer=smk.input.get("answer"),
        answer_curve=smk.input.get("answer_curve"), room_scores=smk.input.get("rooms"),
    )
    log.info("front page %s, %s", smk.output.front, smk.output.summary_md)
