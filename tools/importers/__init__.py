"""Independent FMI importers: the reference results an FMU ships (make_reference) and the
check that runs every FMU through the importers (check)."""
