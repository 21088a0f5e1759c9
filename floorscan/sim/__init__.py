"""The synthetic buildings and their simulated recordings (stage ``simulate``)."""
