// placeholder: replaced by the import implementation
