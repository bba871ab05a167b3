"""The shipped Foxglove layout names what the live view serves, under the names a recording has them."""

import json
from pathlib import Path

from matrix_core import topics
from matrix_core.datasets.matrix_conventions import MATRIX_VIEWS
from matrix_live_view.live_view_node import channel_kinds

LAYOUT = Path(__file__).resolve().parents[1] / 'config' / 'foxglove_layout.json'


def test_every_panel_shows_a_served_or_recorded_topic():
    layout = json.loads(LAYOUT.read_text())
    served = channel_kinds(MATRIX_VIEWS)
    panels = layout['configById']
    three_d = next(v for k, v in panels.items() if k.startswith('3D!'))
    assert {'/live_view/scene', '/live_view/tracks', '/bev_heatmap'} <= set(three_d['topics'])
    for topic in three_d['topics']:
        assert topic in served or topics.topic_type(topic)  # a live channel, else a graph topic (/markers)
    images = sorted(v['imageMode']['imageTopic'] for k, v in panels.items() if k.startswith('Image!'))
    assert images == sorted(topics.absolute(v, topics.OVERLAY_COMPRESSED) for v in MATRIX_VIEWS)
    assert all(served[t] == 'image' for t in images)

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node['first']) + leaves(node['second'])

    assert sorted(leaves(layout['layout'])) == sorted(panels)  # every panel placed once
