"""The model of a lid: the mechanism's closure (kinematics), its force elements, the reduced
equation of motion (dynamics) and the CasADi model that joins them (:class:`~softclose.model.lid.LidModel`).
"""
