"""Code only validation uses: second formulations of the model from textbook mechanics
(:mod:`.textbook`) and the stress survey (:mod:`.stress`).
"""
