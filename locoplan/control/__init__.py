"""locoplan.control"""
