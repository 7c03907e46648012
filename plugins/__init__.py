"""Built-in plugins: sandmod's own behaviour, written against the public hooks."""
