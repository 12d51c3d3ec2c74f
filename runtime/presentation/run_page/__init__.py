"""The page of one run (report.html beside events.csv): ``rendering`` renders it from what
``run_data`` reads of the run's folder, with ``run_plots``. It may import observation and the
contracts; it must never import campaigns' store or run a mission.
"""

from rei.runtime.presentation.run_page.rendering import write_run_page

__all__ = ["write_run_page"]
