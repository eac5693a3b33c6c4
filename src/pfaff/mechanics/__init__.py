"""The model stage: a system described as data (coordinates, families, pieces), validated eagerly.

No derivation here: :mod:`pfaff.derive` turns the description into equations.
"""
