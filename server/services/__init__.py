"""The app's services: the corpus, the model registry, the Csc survey and describing recordings."""
