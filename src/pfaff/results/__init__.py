"""Results: the Trajectory of a simulation, its figures and files, and the ring figure of the demo."""
