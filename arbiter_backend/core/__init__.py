"""Pure logic: no I/O, no threads of its own, no Textual. Time is passed in."""
