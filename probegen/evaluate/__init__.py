"""Returned points against the spec: compensation, fits, characteristics, verdicts, ingest."""
