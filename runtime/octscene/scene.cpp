// placeholder: replaced by the scene implementation
