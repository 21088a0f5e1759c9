"""Figures and the report (stage ``figures``)."""
