"""The subcommands (compare, stats, topics): each its own command line over the session side, no Textual."""
