"""Model registry: name -> constructor. Add a model by adding an entry, never by an if/elif on names."""

from matrix_core.bev.model import BevFusionNet

MODELS = {
    'bev_small': lambda temporal=True: BevFusionNet(
        feat_channels=32, encoder_width=32, bev_channels=64, temporal=temporal
    ),
    'bev_tiny': lambda temporal=True: BevFusionNet(
        feat_channels=16, encoder_width=16, bev_channels=32, temporal=temporal
    ),
}


def build_model(name: str, temporal: bool = True):
    """Instantiate a registered model; raises ValueError listing the known names."""
    try:
        factory = MODELS[name]
    except KeyError:
        raise ValueError(f'unknown model {name!r}; known: {sorted(MODELS)}') from None
    return factory(temporal=temporal)
