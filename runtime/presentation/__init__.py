"""Presentation: what a person reads. ``campaign_report`` (the thesis's tables, plots, the
HTML report of a campaign), ``run_page`` (the page of one run), ``junit`` (JUnit XML for CI),
``live`` (`rei watch` in a terminal and a Foxglove server), with the ``maps``, ``figures``,
``signals`` and ``templating`` both pages share (templates in ``templates/``).

It may import campaigns, runs' results, observation, the bus and the contracts; it never runs
a mission, never judges (it shows the one judgement) and never reaches pybullet.
"""
