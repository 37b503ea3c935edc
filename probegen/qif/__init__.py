"""QIF 3 results: export of ingested runs and DMIS output, and validation against the XSD set."""
