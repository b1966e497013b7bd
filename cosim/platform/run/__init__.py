"""A scene run: wired into the platform's system (system: the one wiring table), its drives
designed for their legs (tuning), run on the engine and reported (runner), judged against a
converged run (accuracy), as a sweep's target (sweep) and in libcosim (libcosim)."""
