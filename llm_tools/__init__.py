"""llm_tools"""
