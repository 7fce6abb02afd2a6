"""Numerical methods the model and the simulation share: the fixed-step integrators
(each with its order) and the root and peak searches of events."""
