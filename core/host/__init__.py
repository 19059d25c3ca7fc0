"""The plugin host: pluggy's hooks, the adapter protocol, the conventions every renderer keeps
(`check`, `remap check`), the analytic images they are checked against, and the pytest kit that
runs them (`testing`). Imports only the data room."""
