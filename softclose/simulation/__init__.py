"""Closing strokes: the fixed-step integrators, the simulator and its C kernel, the adaptive
reference, statics (hold and opening force) and the stroke's result.
"""
