"""The app's one job system: `manager.JobManager` runs the kinds of `kinds` and keeps them in `store`."""
