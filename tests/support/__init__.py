"""Stand-ins, emulators and helpers the tests share (none of it ships in the package)."""
