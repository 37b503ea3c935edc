"""Statistical process control on the history of a characteristic: capability and control charts."""
