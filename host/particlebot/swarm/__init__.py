"""The swarm as the base station knows and commands it: the public API (Swarm) and its parts."""
