"""Pydantic schemas of the REST API, one module per resource: what clients send and receive."""
