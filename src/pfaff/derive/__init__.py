"""The derivation stage: templates -> symbolic blocks (M, h, Q, A, b, bias), the rank check, work
accounting, reduction to minimal coordinates, and code generation into the numeric stage."""
