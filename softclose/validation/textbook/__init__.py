"""Textbook four-bar analyses beyond the lid (seeds 002-004) and an absolute-coordinate lid check.

- driven_fourbar: planar absolute-coordinate kinematics and constrained dynamics; the driven four-bar.
- lid_absolute: the lid as three bodies with Lagrange multipliers (independent check of the EOM).
- linearisation: closed-form four-bar position and the linearised lever ratio.
- synthesis: five-precision-point synthesis by homotopy continuation (optional: bertini2).
"""
