"""The operator loop: the station's screen and keys around the units it calibrates.

One unit lifecycle serves both front-ends: the one-port station and the multi-slot
fixture (:mod:`.fixture`).
"""
