"""The paper's simulation studies (SI S9): definitions, a Dask sweep engine, reports."""
