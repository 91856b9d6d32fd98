"""Reports, tables and figures, read back from results stores only (nothing is
recomputed here, and no report imports the experiment that wrote its data), and
pictures of worlds, episodes and capabilities; ``copi watch``'s episode, decision by
decision."""

from __future__ import annotations

from copi.reports._benchmark import DEFAULT_AGAINST, read_benchmark, write_benchmark_report
from copi.reports._capabilities import fig2_operators, save_capability_figures
from copi.reports._figures import (
    finish_figure,
    new_figure,
    save_episode_gif,
    save_episode_png,
    save_overview_png,
    save_plan_png,
)
from copi.reports._lifelong import lifelong_blocks, lifelong_report_paths, write_lifelong_report
from copi.reports._navigation import Report, summarize, summarize_games, warnings_for, write_report
from copi.reports._watch import (
    FORMATS,
    Step,
    WatchedEpisode,
    check_frames,
    save_watch,
    watch_episode,
)

__all__ = [
    "DEFAULT_AGAINST",
    "FORMATS",
    "Report",
    "Step",
    "WatchedEpisode",
    "check_frames",
    "fig2_operators",
    "finish_figure",
    "lifelong_blocks",
    "lifelong_report_paths",
    "new_figure",
    "read_benchmark",
    "save_capability_figures",
    "save_episode_gif",
    "save_episode_png",
    "save_overview_png",
    "save_plan_png",
    "save_watch",
    "summarize",
    "summarize_games",
    "warnings_for",
    "watch_episode",
    "write_benchmark_report",
    "write_lifelong_report",
    "write_report",
]
