"""REI's runtime: what runs a test, observes it and reports on it, as wings that import
downward only (pyproject.toml's [tool.importlinter] states the rules; tests/test_layering.py
keeps them):

    commands/       `rei`'s sub-commands: argparse and printing, calling the wings below
    presentation/   the campaign report, a run's page, JUnit XML, the live views
    campaigns/      many runs: planning, engines, the results store, search, shrink, clusters
    runs/           one run as a session: its configuration, supervision, cache, warm workers
    observation/    judging a stream: the runtime model, the automata and their host, the
                    evaluator, the one stream judgement, recordings (REI's and foreign)
    simulation/     the run loop on one clock: physics, sensors, humans, faults, the mission
                    executor, the sampler, assembling a run (the only wing with pybullet)
    bus/            the Zenoh hive and its ROS 2 profile (bus/ros2/); beside simulation
    robot/          the controller contract and checker, the host, the watchdog, selection,
                    the reference navigator (robot/navigator/)
    platform/       child processes, scratch folders, fork servers
    contracts       at this root: messages/, trace/, artifacts/, raycast, results, errors

Where a new part goes: a new sensor in simulation/sensors/ (its loop component in
simulation/loop/, what it measures in messages/); a new requirement in the default .vepl, its
query in observation/model/ and its verdict rule in observation/evaluator/; a new campaign
engine in campaigns/engines.py (the ``CampaignEngine`` protocol); a new report section in
presentation/campaign_report/ (or presentation/run_page/ for one run).
"""
