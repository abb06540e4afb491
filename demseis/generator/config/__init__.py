"""What a config means: parameters, the parsed config, the runs drawn from it, its store's layout."""
