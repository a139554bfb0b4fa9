"""Tools around the library: the ``trajplan`` command, benchmarks, figures and the demo."""
