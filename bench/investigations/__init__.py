"""Scripts that answer one question each behind a default, cited by docs/design/ (the
identifier's filter, errors at velocity reversals, the robots' velocity bank, online
friction and MFF at rest)."""
