"""The Textual shell: the app, its screens, widgets, plots and messages over the session side."""
