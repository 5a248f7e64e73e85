"""The kinds of rig: one registry (:mod:`twin.kinds.registry`) of what every command does with a
rig's stores, found by the rig name the stores record; the spectral gonioreflectometer
(:mod:`twin.kinds.gonio`) and the LED dome (:mod:`twin.kinds.dome`).
"""
