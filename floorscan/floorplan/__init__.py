"""Floor plans (stage ``floorplan``)."""
