"""The ``matrix-tracker`` command line tool."""
