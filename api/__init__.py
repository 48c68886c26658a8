"""The results server: a REST API over the results database (``create_app``)."""
