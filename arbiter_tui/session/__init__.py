"""The robot session: what drives the robot and records what it did, with no Textual (the shell shows it)."""
