"""The feature spec: the model of a measuring job, its in-process actions, read from TOML."""
