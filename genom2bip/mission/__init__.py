"""Missions: the decisional layer's requests, waits and expectations, sent to a controller through its client."""
