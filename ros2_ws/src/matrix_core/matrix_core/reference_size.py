"""The image size every pixel quantity given without one is stated at: that of MATRIX's cameras (the paper's,
1920 x 1080). Registration criteria, simulated noise and JPEG quality, texel sizes, the drones' pixel errors
and drawing sizes are given at this width and scaled by ``width / REFERENCE_WIDTH`` for other images."""

REFERENCE_WIDTH = 1920  # px
REFERENCE_HEIGHT = 1080  # px
