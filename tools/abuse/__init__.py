"""Abuse tools: sanitizer, valgrind and fuzz runs, the soak, and the raw FMI access
(abuse_fmi) shared by them and tests/abuse."""
