"""The protocol generator: parse.py reads shared/protocol.toml once, emit_cpp.py and
emit_python.py each write one language from what it read (tools/gen_protocol.py runs them)."""
