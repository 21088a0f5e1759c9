"""The HTML pages of a result rendered from Jinja2 templates (``templates/`` beside this
module): :func:`render` gives a template ONE object, the dataclass of what its page
shows (:class:`floorscan.figures.report.FrontPage`,
:class:`floorscan.figures.map_page.MapFrontPage`,
:class:`floorscan.figures.index_page.IndexPage`,
:class:`floorscan.figures.summary_page.SummaryPage`), and autoescapes every value; the only
markup that passes unescaped is what the page's object marks as
:class:`markupsafe.Markup` (the plan's SVG, checked by
:func:`floorscan.figures.report.inline_svg`). :class:`OutputFile` is a file a page
names: a link relative to the page's folder when the file exists, its name and "not
made" when it does not, never a dead link; :data:`INDEX` and :func:`report_file` are
the two a dataset's pages name at the top.

To add a page: a dataclass of what it shows, a template ``templates/<name>.html.j2``
that extends ``_front_base.html.j2`` (the style, the title, the links back to the
index and to the report) or stands alone, and a call of :func:`render`.
Source: Jinja2 3.1 (``PackageLoader``, ``autoescape``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path


@dataclass(frozen=True)
class OutputFile:
    """A file a page names.

    Attributes
    ----------
    label : str
        What it is (``"IFC (BIM)"``).
    href : str
        Its path relative to the page's folder, POSIX (``"selection/scans.csv"``).
    exists : bool
        Whether it existed when the page was written: only then is it a link.
    """

    label: str
    href: str
    exists: bool

    @property
    def name(self) -> str:
        """The file's name as the page shows it (its path from the page's folder)."""
        return self.href


def output_file(label: str, path: str | os.PathLike, page_dir: str | os.PathLike) -> OutputFile:
    """:class:`OutputFile` of ``path`` (relative to the working directory, or absolute)
    as a page in ``page_dir`` links it.

    Parameters
    ----------
    label : str
    path : path
        The file.
    page_dir : path
        The folder of the page (``results/<dataset>``).

    Returns
    -------
    OutputFile
    """
    href = Path(os.path.relpath(Path(path).absolute(), Path(page_dir).absolute())).as_posix()
    return OutputFile(label, href, Path(path).exists())


@lru_cache(maxsize=1)
def environment():
    """The pages' Jinja2 environment: templates of this package, autoescape on, an
    undefined name an error.

    Returns
    -------
    jinja2.Environment
    """
    from jinja2 import Environment, PackageLoader, StrictUndefined

    return Environment(
        loader=PackageLoader("floorscan.figures", "templates"),
        autoescape=True,
        undefined=StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
    )


def render(template: str, page) -> str:
    """Render ``templates/<template>`` with the one object ``page`` (named ``page``).

    Parameters
    ----------
    template : str
        File name under ``floorscan/figures/templates``.
    page : object
        The dataclass of what the page shows.

    Returns
    -------
    str
        The HTML document.
    """
    return environment().get_template(template).render(page=page)


#: The index of every dataset, from a dataset's folder (``results/<dataset>/``): always
#: linked (the run writes it, :func:`floorscan.figures.index_page.write_index`).
INDEX = OutputFile("index of every dataset", "../index.html", True)


def report_file(page_dir: "str | os.PathLike") -> OutputFile:
    """Snakemake's report of the run (``results/report.html``) as the page in
    ``page_dir`` names it."""
    return output_file("report", Path(page_dir).parent / "report.html", page_dir)
