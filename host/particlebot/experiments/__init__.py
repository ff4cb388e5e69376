"""Experiments as files: trials run one after another through the Swarm API (`particlebot run`)."""
