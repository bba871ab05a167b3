"""Registry of feature backends: name -> factory(settings). Add a backend by adding an entry here."""

from functools import partial


def _sift(settings):
    from matrix_core.register.backend_sift import SiftBackend

    return SiftBackend(settings.scale, settings.contrast_threshold)


def _gftt_affnet(descriptor: str, settings):
    from matrix_core.register.backend_kornia import GfttAffNetBackend

    return GfttAffNetBackend(descriptor, settings.scale)


BACKENDS = {
    'sift': _sift,
    'gftt_affnet_hardnet': partial(_gftt_affnet, 'hardnet'),
    'gftt_affnet_hardtfeat': partial(_gftt_affnet, 'hardtfeat'),
    'gftt_affnet_sift': partial(_gftt_affnet, 'sift'),
}


def make_backend(settings):
    """The backend named by ``settings.backend``, configured from ``settings`` (a RegisterSettings)."""
    try:
        factory = BACKENDS[settings.backend]
    except KeyError:
        raise ValueError(f'unknown backend {settings.backend!r}; choose one of {sorted(BACKENDS)}') from None
    return factory(settings)
