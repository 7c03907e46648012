"""sandmod's command line and developer tools."""
