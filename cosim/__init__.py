"""Co-simulation of an electrically driven 6-DOF Stewart platform (FMI 2.0, fmpy)."""
