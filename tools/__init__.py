"""Project tools run as modules from the repository root (``python -m tools.abuse.soak``);
abuse/, dist/ and importers/ also hold the shell scripts and C drivers of each."""
