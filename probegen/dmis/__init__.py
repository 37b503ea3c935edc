"""The DMIS language reader (lexer, statements, expressions), shared by post, sim and results."""
