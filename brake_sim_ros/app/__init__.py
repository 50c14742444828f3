"""Composition roots: each builds one program from the library's parts (arguments, signals,
sinks, nodes). They sit on top, beside the CLI; nothing in the library imports them.
"""
