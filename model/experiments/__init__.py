"""The experiment machinery around the model: the paper's evaluation protocol (4.2), run store, sweeps
(Fig. 3, Fig. 9) and the report. Functions the CLI, the server's jobs and Ray workers call alike."""
