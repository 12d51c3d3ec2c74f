"""The order in which reports list the thesis's signals (Table 3's order; any other after
them, by name): the campaign's tables and plots and a run's page list them alike."""

SIGNAL_ORDER = ("SIG_MISSION_BEGIN", "SIG_MISSION_END", "SIG_MISSION_TASK_START",
                "SIG_MISSION_TASK_SUCCESS", "SIG_MISSION_TASK_FAIL",
                "SIG_GEOM_FAR_TRANSIT_CLOSE", "SIG_GEOM_CLOSE_TRANSIT_FAR",
                "SIG_GEOM_CLOSE_TRANSIT_COLLISION", "SIG_GEOM_COLLISION_TRANSIT_CLOSE",
                "SIG_LASER_CLOSE_TRANSIT_COLLISION", "SIG_LASER_COLLISION_TRANSIT_CLOSE")
