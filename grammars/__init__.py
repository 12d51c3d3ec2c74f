"""textX grammars of the REI languages (data only): room.tx, mission.tx, common.tx."""
