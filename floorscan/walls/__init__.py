"""Wall extraction (stage ``walls``)."""
