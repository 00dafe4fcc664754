"""Cross-platform distribution checks: the reference plan of an FMU for run_reference.c."""
