"""The continuous and discrete references simgrip's simulations are checked against (no MuJoCo here).

:mod:`simgrip.reference.elastica` solves the planar elastica boundary-value
problems of the paper (free rod, Grips I-III); :mod:`simgrip.reference.discrete`
holds the paper's discrete energy, the hinge-chain minimiser and the stability
test.
"""
