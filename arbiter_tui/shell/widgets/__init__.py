"""The console's widgets, each showing its part of the frame: text widgets (``text``), plots
(``plots``), and the analytics, topics and latency screens' own (``analytics``, ``topics``,
``latency``). Screens compose them; no widget imports a screen or a dialog."""
