"""The page of one run (report.html beside events.csv): ``page`` renders it from what
``run_data`` reads of the run's folder, with ``run_plots``. It may import observation and the
contracts; it must never import campaigns' store or run a mission.
"""
