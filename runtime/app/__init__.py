"""The application layer: command line, model commands, pictures, precompile."""
