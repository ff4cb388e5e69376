"""The base-station console: a live table of every particle heard, and commands to send them."""
