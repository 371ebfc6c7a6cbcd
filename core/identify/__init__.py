"""Identification: the material (and the missing effects) from measured data.

:mod:`.fit` fits the parameters, :mod:`.uncertainty` gives their intervals and
:mod:`.diagnose` names the effect the model lacks.
"""
