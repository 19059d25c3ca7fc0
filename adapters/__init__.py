"""Built-in renderer adapters. Each subpackage is a plugin registered through the
``brdfremap`` entry-point group, exactly like a third-party adapter."""
