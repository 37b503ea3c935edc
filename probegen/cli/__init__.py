"""The command line: argument parsing, exit codes, progress bars, messages."""
