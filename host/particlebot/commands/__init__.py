"""The particlebot subcommands, one thin module each; cli.py parses arguments and dispatches."""
