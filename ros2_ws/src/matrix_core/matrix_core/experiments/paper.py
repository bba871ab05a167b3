"""The MATRIX paper's numbers that our experiments are compared with (percent), as quoted in issue #8
of this project (the issue is the source; the paper's tables give more digits and more rows)."""

SOURCE = 'MATRIX paper, as quoted in issue #8 of this repository'

# Experiment 2, complex variant with moving drones.
STATIC_TRACKTACULAR = {'moda': 5.7, 'mota': 31.0}       # TrackTacular (static-camera assumption)
PROPOSED_COMPLEX = {'moda': 89.0, 'mota': 88.5}         # the proposed method ("~89 %", "~88.5 %")

# Experiment 3, modified variant trained on 50 % of its frames: MODA from scratch -> from the complex model.
TRANSFER_MODA = {'scratch': 54.0, 'pretrained': 69.0}

# Experiment 4, camera dropout: "> 80 % MODA at 0.25, ~45 % / ~36 % at 0.75". The issue does not say
# which two series the 0.75 figures belong to; they are shown as quoted.
DROPOUT_MODA_AT_025_MIN = 80.0
DROPOUT_AT_075 = (45.0, 36.0)
DROPOUT_AT_075_TEXT = '~45 % / ~36 %'
