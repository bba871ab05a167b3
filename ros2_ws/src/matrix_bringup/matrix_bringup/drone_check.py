"""Leaving out of the graph a drone whose start-up inputs (the dataset folder's references, or the site file's)
cannot be read (``matrix_core.datasets.drone_inputs``):
the other drones, fuse and the recorder run without it, and the replay's end names it (``run_graph``,
``full_graph.launch.py``)."""

from dataclasses import replace

from matrix_bringup.graph import check_sources, graph_nodes
from matrix_core.datasets import DatasetError
from matrix_core.datasets.drone_inputs import left_out_text, open_references, unreadable_drones
from matrix_core.site.parameter import named_site

__all__ = ['LEFT_OUT_EXIT', 'left_out_text', 'ran_without_text', 'without_unreadable_drones']

LEFT_OUT_EXIT = 5  # run_graph's exit code when every frame played but some drone was left out at start
# (``ros2 launch`` has one failure code, 1: the launch exits with it, saying the same line)


def without_unreadable_drones(settings) -> tuple:
    """(GraphSettings without the drones whose reference cannot be read, view -> why each was left out);
    ValueError on bad settings (``graph.graph_nodes``) and when no drone is left."""
    site = named_site(settings.site)
    check_sources(settings, site)
    try:  # the dataset folder's references, else the site file's
        dataset = open_references(settings.dataset, None if settings.dataset else site)
    except DatasetError as exc:  # a settings error like any other: one line before anything starts
        raise ValueError(f'{"dataset" if settings.dataset else "site"}: {exc}') from None
    # then every other setting (the bag, the views it has, the site): a view named by mistake is a settings
    # error, not a drone to leave out
    graph_nodes(settings)
    left_out = unreadable_drones(dataset, settings.views)
    if not left_out:
        return settings, {}
    kept = [v for v in settings.views if v not in left_out]
    if not kept:
        raise ValueError(f'no drone can start: {left_out_text(left_out)}')
    return replace(settings, views=kept), left_out


def ran_without_text(left_out: dict) -> str:
    """The end of a replay that ran without some drones: 'ran without drone(s) D2: D2 left out (why)'."""
    return f'ran without drone(s) {", ".join(sorted(left_out))}: {left_out_text(left_out)}'
